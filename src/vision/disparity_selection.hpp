#pragma once
// Turns one row of aggregated matching costs into disparities: the
// winner-take-all disparity, kept only if it is unique (every disparity more
// than one step away costs uniqueness_percent more) and if the right view's
// winner at the matched column agrees within lr_max_diff (the left-right
// check: an occluded pixel sees, in the other eye, a surface that prefers
// another disparity), refined by the parabola through the costs at d - 1,
// d, d + 1. Integer arithmetic only, with the rounding written out, so the
// fraction is the same on every machine.
#include <cstdint>

namespace rtfuse::vision {

// The workspace of one row, sized for the widest row: width values each,
// the right view's width + disparities. The right view's are stored from
// the right (index width - 1 - x), so that a left pixel's disparities meet
// them forwards in memory.
struct DisparityRowScratch {
  std::int16_t* left_best = nullptr;
  std::int16_t* right_best = nullptr;
  std::int16_t* right_cost = nullptr;
};

// sums[x * disparities + d] for x < width (each below 0x7fff); disparities at column x are
// searched up to min(disparities - 1, x) (further would look left of the
// right image). out[x]: disparity * kDisparityScale in the row's pixels, or
// -1. lr_max_diff < 0: no left-right check; uniqueness_percent 0: none.
void select_disparity_row(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                          int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept;
// The same with plain code, for the test that the vector versions agree.
void select_disparity_row_portable(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                   int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept;

// The parabola's vertex as a fraction of a pixel in 1/kDisparityScale,
// rounded half away from zero, from the costs left of, at and right of the
// minimum (|result| <= kDisparityScale / 2).
int subpixel_offset(int cost_left, int cost_min, int cost_right) noexcept;

}  // namespace rtfuse::vision
