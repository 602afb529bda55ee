#pragma once
// The disparity selection of disparity_selection.hpp (winner, uniqueness,
// left-right check, parabola fraction) with the same results, done while a
// pixel's sums are still in registers in the matcher's last pass, so the
// sums need no second trip through memory (PackedWinner, in
// semi_global_kernels.hpp with the rest of the matcher's per-instruction-set
// loops).
//
// Each sum is packed with its disparity, (sum << shift) | d, biased by
// -32768 so that signed 16-bit lanes (SSE2 has no unsigned 16-bit min)
// order them as unsigned: one min then finds the least sum and, among
// equal sums, the smallest disparity, which is the tie rule of the
// two-pass selection. That needs sum << shift + d < 65535
// (packed_winner_fits); the matcher falls back to the two-pass selection
// otherwise.
//
// Uniqueness needs the least sum more than one step from the winner. Lane
// i holds the disparities i mod the lane count (8, or AVX2's 16), and three
// neighbouring disparities fall in three different lanes, so per lane the
// least and second least packed values are enough: the second stands in
// where the least is the window's.
//
// The right view keeps, per right column, the least packed value over the
// left pixels that match it (its winner and tie rule as in
// disparity_selection.hpp): one min per vector of disparities.
#include <cstdint>

#include "vision/disparity_selection.hpp"

namespace rtfuse::vision {

// Bits that hold a disparity below `disparities`.
inline int packed_winner_shift(int disparities) noexcept {
  int s = 0;
  while ((1 << s) < disparities) ++s;
  return s;
}

// Whether sums up to max_sum pack with disparities below `disparities`
// (0x7fff, the largest biased value, stays free to mean "no cost").
inline bool packed_winner_fits(int max_sum, int disparities) noexcept {
  const int shift = packed_winner_shift(disparities);
  return shift <= 14 && (static_cast<long long>(max_sum) << shift) + disparities - 1 < 0xffff;
}

// A whole row through PackedWinner, in the matcher's order (right to
// left), with select_disparity_row's arguments: on the build's baseline
// lanes (SSE2, NEON), on plain lanes, and on AVX2's (false, and nothing
// written, where this CPU has no AVX2 or disparities is not a multiple of
// 16). The tests hold them against select_disparity_row.
void select_disparity_row_packed(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                 int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept;
void select_disparity_row_packed_portable(const std::int16_t* sums, int width, int disparities,
                                          int uniqueness_percent, int lr_max_diff, const DisparityRowScratch& scratch,
                                          std::int16_t* out) noexcept;
bool select_disparity_row_packed_avx2(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                      int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept;

}  // namespace rtfuse::vision
