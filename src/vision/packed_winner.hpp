#pragma once
// The disparity selection of disparity_selection.hpp (winner, uniqueness,
// left-right check, parabola fraction) with the same results, done while a
// pixel's sums are still in registers in the matcher's last pass, so the
// sums need no second trip through memory.
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
// i holds the disparities i mod 8, and three neighbouring disparities fall
// in three different lanes, so per lane the least and second least packed
// values are enough: the second stands in where the least is the window's.
//
// The right view keeps, per right column, the least packed value over the
// left pixels that match it (its winner and tie rule as in
// disparity_selection.hpp): one min per eight disparities.
#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "vision/disparity_image.hpp"
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

template <class L>
class PackedWinner {
 public:
  using V = typename L::V;
  static constexpr std::int16_t kNone = 0x7fff;

  // right: the row's right-view scratch, width + disparities values,
  // indexed width - 1 - (right column) as in DisparityRowScratch.
  PackedWinner(int width, int disparities, int uniqueness_percent, std::int16_t* right) noexcept
      : width_(width),
        disparities_(disparities),
        uniqueness_percent_(uniqueness_percent),
        shift_(packed_winner_shift(disparities)),
        right_(right) {
    static const std::int16_t kLane[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    lane_bias_ = L::add(L::load(kLane), L::splat(-32768));
    std::fill(right_, right_ + width + disparities, kNone);
  }

  // Starts left pixel x; its sums follow eight disparities a call, in order.
  void begin(int x) noexcept {
    x_ = x;
    cut_ = x < disparities_ - 1;
    last_ = L::splat(x - 32768);
    bias_ = lane_bias_;
    min1_ = min2_ = L::splat(kNone);
    right_x_ = right_ + (width_ - 1 - x);
  }

  // Sums of disparities k .. k + 7.
  void add(int k, V sums) noexcept {
    V packed = L::add(L::shl(sums, shift_), bias_);
    // Past x the disparity looks left of the right image.
    if (cut_) packed = L::select(L::gt(bias_, last_), L::splat(kNone), packed);
    L::store(right_x_ + k, L::min(L::load(right_x_ + k), packed));
    min2_ = L::min(min2_, L::max(min1_, packed));
    min1_ = L::min(min1_, packed);
    bias_ = L::add(bias_, L::splat(8));
  }

  // The pixel's disparity * kDisparityScale or -1 into *out, its winner or
  // -1 into *best_out; sums: the pixel's disparities' sums (for the
  // fraction).
  void finish(const std::int16_t* sums, std::int16_t* out, std::int16_t* best_out) const noexcept {
    const int mask = (1 << shift_) - 1;
    const unsigned least_packed = unpack(L::hmin(min1_));
    const int best = static_cast<int>(least_packed) & mask, least = static_cast<int>(least_packed >> shift_);
    if (uniqueness_percent_ > 0) {
      const V d = L::bit_and(min1_, L::splat(mask));
      const V near = L::select(L::gt(d, L::splat(best - 2)), L::gt(L::splat(best + 2), d), L::splat(0));
      const int second = L::hmin(L::select(near, min2_, min1_));
      if (second != kNone && static_cast<int>(unpack(second) >> shift_) < uniqueness_bar(least)) {
        *out = -1;
        *best_out = -1;
        return;
      }
    }
    *best_out = static_cast<std::int16_t>(best);
    const int dmax = std::min(disparities_ - 1, x_);
    const int fraction = best > 0 && best < dmax ? subpixel_offset(sums[best - 1], least, sums[best + 1]) : 0;
    *out = static_cast<std::int16_t>(best * kDisparityScale + fraction);
  }

  // After every pixel of the row: drops those whose right-view winner
  // differs by more than lr_max_diff (< 0: no check).
  void check_right(const std::int16_t* best, int lr_max_diff, std::int16_t* out) const noexcept {
    if (lr_max_diff < 0) return;
    const int mask = (1 << shift_) - 1;
    for (int x = 0; x < width_; ++x) {
      const int d = best[x];
      if (d < 0) continue;
      const int right_best = static_cast<int>(unpack(right_[width_ - 1 - x + d])) & mask;
      if (std::abs(right_best - d) > lr_max_diff) out[x] = -1;
    }
  }

 private:
  static unsigned unpack(int biased) noexcept { return static_cast<unsigned>(biased + 32768); }
  // s * (100 - u) < least * 100 for an integer s exactly when s < this.
  int uniqueness_bar(int least) const noexcept {
    const int keep = 100 - uniqueness_percent_;
    return (least * 100 + keep - 1) / keep;
  }

  int width_, disparities_, uniqueness_percent_, shift_;
  std::int16_t* right_;
  std::int16_t* right_x_ = nullptr;
  int x_ = 0;
  bool cut_ = false;
  V lane_bias_, last_, bias_, min1_, min2_;
};

// A whole row through PackedWinner, in the matcher's order (right to
// left): the tests hold it against select_disparity_row.
template <class L>
void select_disparity_row_packed(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                 int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  PackedWinner<L> winner(width, disparities, uniqueness_percent, scratch.right_cost);
  for (int x = width - 1; x >= 0; --x) {
    const std::int16_t* s = sums + static_cast<std::ptrdiff_t>(x) * disparities;
    winner.begin(x);
    for (int k = 0; k < disparities; k += 8) winner.add(k, L::load(s + k));
    winner.finish(s, out + x, scratch.left_best + x);
  }
  winner.check_right(scratch.left_best, lr_max_diff, out);
}

}  // namespace rtfuse::vision
