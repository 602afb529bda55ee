#include "vision/disparity_selection.hpp"

#include <algorithm>
#include <cstdlib>

#include "vision/disparity_image.hpp"
#include "vision/simd_i16.hpp"

namespace rtfuse::vision {
namespace {

constexpr std::int16_t kNoCost = 0x7fff;

// s * (100 - u) < least * 100 for an integer s exactly when s < this
// (clamped: every sum is below it then).
int uniqueness_bar(int least, int uniqueness_percent) noexcept {
  const int keep = 100 - uniqueness_percent;
  return std::min((least * 100 + keep - 1) / keep, static_cast<int>(kNoCost));
}

// One column, eight disparities a step; disparities past x (left of the
// right image) count as kNoCost. Ties go to the smallest disparity: each
// lane keeps its first minimum, then the smallest index among the lanes
// that hold the least.
template <class L>
void select_column(const std::int16_t* s, int x, int width, int disparities, int uniqueness_percent,
                   const DisparityRowScratch& scratch, int* best_out, int* least_out, bool* unique_out) noexcept {
  using V = typename L::V;
  static const std::int16_t kLane[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  const V step = L::splat(8), last = L::splat(x), none = L::splat(kNoCost);
  const bool cut = x < disparities - 1;
  const int j0 = width - 1 - x;
  std::int16_t* rc = scratch.right_cost + j0;
  std::int16_t* rb = scratch.right_best + j0;
  V idx = L::load(kLane), least_v = none, best_v = L::splat(0);
  for (int k = 0; k < disparities; k += 8) {
    const V c = cut ? L::select(L::gt(idx, last), none, L::load(s + k)) : L::load(s + k);
    const V r = L::load(rc + k);
    const V better_right = L::gt(r, c);
    L::store(rc + k, L::select(better_right, c, r));
    L::store(rb + k, L::select(better_right, idx, L::load(rb + k)));
    const V better = L::gt(least_v, c);
    least_v = L::select(better, c, least_v);
    best_v = L::select(better, idx, best_v);
    idx = L::add(idx, step);
  }
  const int least = L::hmin(least_v);
  const int best = L::hmin(L::select(L::gt(least_v, L::splat(least)), L::splat(kNoCost), best_v));
  bool unique = true;
  if (uniqueness_percent > 0) {
    // The least cost more than one step from the winner.
    const V lo = L::splat(best - 2), hi = L::splat(best + 2), zero = L::splat(0);
    V second = none;
    idx = L::load(kLane);
    for (int k = 0; k < disparities; k += 8) {
      const V near = L::select(L::gt(idx, lo), L::gt(hi, idx), zero);
      const V c = cut ? L::select(L::gt(idx, last), none, L::load(s + k)) : L::load(s + k);
      second = L::min(second, L::select(near, none, c));
      idx = L::add(idx, step);
    }
    unique = L::hmin(second) >= uniqueness_bar(least, uniqueness_percent);
  }
  *best_out = best;
  *least_out = least;
  *unique_out = unique;
}

template <class L>
void select_row(const std::int16_t* sums, int width, int disparities, int uniqueness_percent, int lr_max_diff,
                const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  std::fill(scratch.right_cost, scratch.right_cost + width, kNoCost);
  std::fill(scratch.right_best, scratch.right_best + width, std::int16_t{-1});
  for (int x = 0; x < width; ++x) {
    const std::int16_t* s = sums + static_cast<std::ptrdiff_t>(x) * disparities;
    int best = 0, least = 0;
    bool unique = true;
    select_column<L>(s, x, width, disparities, uniqueness_percent, scratch, &best, &least, &unique);
    if (!unique) {
      out[x] = -1;
      scratch.left_best[x] = -1;
      continue;
    }
    scratch.left_best[x] = static_cast<std::int16_t>(best);
    const int dmax = std::min(disparities - 1, x);
    const int fraction = best > 0 && best < dmax ? subpixel_offset(s[best - 1], least, s[best + 1]) : 0;
    out[x] = static_cast<std::int16_t>(best * kDisparityScale + fraction);
  }
  if (lr_max_diff < 0) return;
  for (int x = 0; x < width; ++x) {
    const int d = scratch.left_best[x];
    if (d < 0) continue;
    // Right column x - d, stored at width - 1 - (x - d).
    if (std::abs(scratch.right_best[width - 1 - x + d] - d) > lr_max_diff) out[x] = -1;
  }
}

}  // namespace

int subpixel_offset(int cost_left, int cost_min, int cost_right) noexcept {
  const int num = (cost_left - cost_right) * kDisparityScale;
  const int den = 2 * std::max(cost_left + cost_right - 2 * cost_min, 1);
  // C++ division truncates towards zero: adding half the divisor with the
  // numerator's sign rounds half away from zero, symmetric in left and right.
  return (num + (num >= 0 ? den / 2 : -(den / 2))) / den;
}

void select_disparity_row(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                          int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  select_row<simd::NativeI16>(sums, width, disparities, uniqueness_percent, lr_max_diff, scratch, out);
}

void select_disparity_row_portable(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                   int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  select_row<simd::PlainI16>(sums, width, disparities, uniqueness_percent, lr_max_diff, scratch, out);
}

}  // namespace rtfuse::vision
