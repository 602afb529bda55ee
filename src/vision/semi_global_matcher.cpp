#include "vision/semi_global_matcher.hpp"

#include <algorithm>
#include <cstring>

#include "vision/census_cost.hpp"
#include "vision/census_transform.hpp"
#include "vision/disparity_selection.hpp"
#include "vision/feature_filters.hpp"
#include "vision/packed_winner.hpp"
#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {

// Path costs are bytes: along a path L(p, d) - min_k L(p-r, k) is at most
// P2, and min_k L(p, k) at most the largest matching cost (31), so with
// P2 <= kMaxP2 every path cost is at most 127: two paths add up in a byte
// before they are widened into the 16-bit sums, and 255 can mark "beyond
// the disparity range" (a step there never wins; adding P1 saturates).
constexpr std::uint8_t kPathBeyondRange = 0xff;
constexpr int kMaxP2 = 127 - kCensusBits;
// Each path row slot: [0] the slot's least cost, [15] and [16 + D] the
// beyond-range values, [16, 16 + D) the costs.
constexpr int kSlotPad = 32;
constexpr int kSlotFirst = 16;
// A cost volume larger than this is refused rather than allocated (3 GB of
// costs and sums).
constexpr long long kMaxCells = 1LL << 30;

// One pixel of two paths: their new costs from their previous pixels' and
// the pixel's matching costs, sixteen disparities a step; the two paths'
// sum (bytes) goes to sink(k, sum of k..k+15). Two paths a sweep (a
// pass's four take two sweeps): with more, their vectors no longer fit the
// sixteen registers of SSE2 and spill.
template <class B, bool kRowPath, class Sink>
inline void update_path_pair(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                             int disparities, typename B::V p1, typename B::V jump, Sink&& sink) noexcept {
  using V = typename B::V;
  // Every candidate is at least the previous least (base), so subtracting
  // it first cannot wrap, and the jump is then the constant P2.
  const V base[2] = {B::splat(prev[0][0]), B::splat(prev[1][0])};
  V least[2] = {B::splat(kPathBeyondRange), B::splat(kPathBeyondRange)};
  // The row path (path 0 if kRowPath): its previous pixel's costs were
  // stored just now, and a load one byte off a recent store cannot be
  // forwarded from the store buffer (a stall of every such load). Its
  // neighbours d - 1 and d + 1 are therefore shifted in from the chunks on
  // either side, loaded where they were stored.
  V row_before = B::splat(kPathBeyondRange), row_at = B::load(prev[0] + kSlotFirst);
  for (int k = 0; k < disparities; k += 16) {
    const V c = B::load(cost + k);
    // Past the range: the slot's beyond-range guard, not written since.
    const V row_after = kRowPath ? B::load(prev[0] + kSlotFirst + k + 16) : row_at;
    V pair = B::splat(0);
#pragma GCC unroll 2
    for (int i = 0; i < 2; ++i) {
      const std::uint8_t* p = prev[i] + kSlotFirst + k;
      const bool row = kRowPath && i == 0;
      const V at = row ? row_at : B::load(p);
      const V before = row ? B::shift_in_before(row_at, row_before) : B::load(p - 1);
      const V after = row ? B::shift_in_after(row_at, row_after) : B::load(p + 1);
      const V m = B::min(B::sub(B::min(B::min(at, B::adds(before, p1)), B::adds(after, p1)), base[i]), jump);
      const V l = B::add(m, c);
      B::store(cur[i] + kSlotFirst + k, l);
      least[i] = B::min(least[i], l);
      pair = B::add(pair, l);
    }
    sink(k, pair);
    if (kRowPath) {
      row_before = row_at;
      row_at = row_after;
    }
  }
  cur[0][0] = static_cast<std::uint8_t>(B::hmin(least[0]));
  cur[1][0] = static_cast<std::uint8_t>(B::hmin(least[1]));
}

// The downward pass's kN paths (2 or 4, the row path first) of one pixel.
// Two paths' sum fits a byte (at most 2 x 127), so with 4 paths in all
// it waits for the upward pass as bytes (pair_sum), half the memory
// traffic; four paths' sum needs the 16-bit sum.
template <class B, int kN>
inline void down_paths(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                       std::int16_t* sum, std::uint8_t* pair_sum, int disparities, typename B::V p1,
                       typename B::V jump) noexcept {
  using V = typename B::V;
  using W = typename B::Wide;
  if (kN == 2) {
    update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [pair_sum](int k, V pair) {
      B::store(pair_sum + k, pair);
    });
    return;
  }
  update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [sum](int k, V pair) {
    W::store(sum + k, B::widen_lo(pair));
    W::store(sum + k + 8, B::widen_hi(pair));
  });
  // Loaded at the addresses and sizes just stored: forwarded from the store
  // buffer.
  update_path_pair<B, false>(prev + 2, cur + 2, cost, disparities, p1, jump, [sum](int k, V pair) {
    W::store(sum + k, W::add(W::load(sum + k), B::widen_lo(pair)));
    W::store(sum + k + 8, W::add(W::load(sum + k + 8), B::widen_hi(pair)));
  });
}

// The upward pass's kN paths of one pixel, added to the downward pass's
// sums (pair_sum with 2 paths a pass, sum with 4) into out.
template <class B, int kN>
inline void up_paths(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                     const std::int16_t* sum, const std::uint8_t* pair_sum, std::int16_t* out, int disparities,
                     typename B::V p1, typename B::V jump) noexcept {
  using V = typename B::V;
  using W = typename B::Wide;
  if (kN == 2) {
    update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [pair_sum, out](int k, V pair) {
      const V down = B::load(pair_sum + k);
      W::store(out + k, W::add(B::widen_lo(down), B::widen_lo(pair)));
      W::store(out + k + 8, W::add(B::widen_hi(down), B::widen_hi(pair)));
    });
    return;
  }
  update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [sum, out](int k, V pair) {
    W::store(out + k, W::add(W::load(sum + k), B::widen_lo(pair)));
    W::store(out + k + 8, W::add(W::load(sum + k + 8), B::widen_hi(pair)));
  });
  update_path_pair<B, false>(prev + 2, cur + 2, cost, disparities, p1, jump, [out](int k, V pair) {
    W::store(out + k, W::add(W::load(out + k), B::widen_lo(pair)));
    W::store(out + k + 8, W::add(W::load(out + k + 8), B::widen_hi(pair)));
  });
}

}  // namespace

const char* to_string(DisparityStatus s) noexcept {
  switch (s) {
    case DisparityStatus::kOk:
      return "ok";
    case DisparityStatus::kNotConstructed:
      return "the matcher's parameters were refused at construction";
    case DisparityStatus::kBadImage:
      return "an image or the output is empty, null or has a stride shorter than its row";
    case DisparityStatus::kSizeMismatch:
      return "left, right and output sizes do not agree";
    case DisparityStatus::kLargerThanWorkspace:
      return "the image is larger than the matcher was constructed for";
    case DisparityStatus::kRangeTooWide:
      return "the disparity range is not narrower than the (downscaled) image";
  }
  return "unknown";
}

struct SemiGlobalMatcher::Workspace {
  Workspace(int w, int h, int d, bool halve)
      : slot(d + kSlotPad),
        cost(new std::uint8_t[static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(d) +
                              kSlotPad]),
        sums(new std::int16_t[static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(d)]),
        reversed_stride(w + d + 32),
        right_reversed(new std::uint8_t[static_cast<std::size_t>(kCensusPlanes) * static_cast<std::size_t>(reversed_stride)]()),
        path_rows(new std::uint8_t[static_cast<std::size_t>(6 * w + 3) * static_cast<std::size_t>(slot)]),
        disparity(w, h),
        left_best(new std::int16_t[static_cast<std::size_t>(w)]()),
        right_best(new std::int16_t[static_cast<std::size_t>(w + d)]()),
        right_cost(new std::int16_t[static_cast<std::size_t>(w + d)]()),
        total(new std::int16_t[static_cast<std::size_t>(d)]()),
        row_sums(new std::int16_t[static_cast<std::size_t>(w) * static_cast<std::size_t>(d)]()),
        speckles(w * h) {
    if (halve) {
      half_left = Plane<std::uint8_t>(w, h);
      half_right = Plane<std::uint8_t>(w, h);
    }
    for (int g = 0; g < kCensusPlanes; ++g) {
      census_left[g] = Plane<std::uint8_t>(w, h);
      census_right[g] = Plane<std::uint8_t>(w, h);
    }
    // Every slot: zero costs between beyond-range guards; the guards are
    // never written again.
    const std::size_t slots = static_cast<std::size_t>(6 * w + 3);
    for (std::size_t i = 0; i < slots; ++i) {
      std::uint8_t* s = path_rows.get() + i * static_cast<std::size_t>(slot);
      std::fill(s, s + slot, std::uint8_t{0});
      s[kSlotFirst - 1] = kPathBeyondRange;
      s[kSlotFirst + d] = kPathBeyondRange;
    }
    for (int r = 0; r < 6; ++r) rows[r] = path_rows.get() + static_cast<std::size_t>(r * w) * static_cast<std::size_t>(slot);
    horizontal[0] = path_rows.get() + static_cast<std::size_t>(6 * w) * static_cast<std::size_t>(slot);
    horizontal[1] = horizontal[0] + slot;
    zero = horizontal[1] + slot;
  }

  int slot;
  std::unique_ptr<std::uint8_t[]> cost;   // [y][x][d]
  std::unique_ptr<std::int16_t[]> sums;   // [y][x][d]
  int reversed_stride;
  std::unique_ptr<std::uint8_t[]> right_reversed;  // per census plane, one row reversed
  std::unique_ptr<std::uint8_t[]> path_rows;
  std::uint8_t* rows[6] = {};        // three directions' previous and current rows
  std::uint8_t* horizontal[2] = {};  // the row path's previous and current pixel
  std::uint8_t* zero = nullptr;      // where a path enters the image
  Plane<std::uint8_t> half_left, half_right;
  Plane<std::uint8_t> census_left[kCensusPlanes], census_right[kCensusPlanes];
  Plane<std::int16_t> disparity;  // matched pixels * kDisparityScale, -1 invalid
  std::unique_ptr<std::int16_t[]> left_best, right_best;
  std::unique_ptr<std::int16_t[]> right_cost;
  std::unique_ptr<std::int16_t[]> total;     // one pixel's complete sums (fused selection)
  std::unique_ptr<std::int16_t[]> row_sums;  // one row's (two-pass selection)
  SpeckleFilter speckles;
};

SemiGlobalMatcher::SemiGlobalMatcher(int max_width, int max_height, const DisparityParams& params) : params_(params) {
  const DisparityParams& p = params;
  if (max_width <= 0 || max_height <= 0) {
    error_ = "the largest image size must be positive";
  } else if (p.downscale != 1 && p.downscale != 2) {
    error_ = "downscale must be 1 (full resolution) or 2 (half)";
  } else if (p.paths != 4 && p.paths != 8) {
    error_ = "paths must be 4 or 8";
  } else if (p.disparities <= 0 || p.disparities > 1024 || p.disparities % (16 * p.downscale) != 0) {
    error_ = p.downscale == 1 ? "disparities must be a multiple of 16 in 16..1024"
                              : "disparities must be a multiple of 32 in 32..1024 with downscale 2";
  } else if (p.disparities / p.downscale >= max_width / p.downscale) {
    error_ = "the disparity range must be narrower than the image: fewer disparities or a wider image";
  } else if (p.p1 < 0 || p.p2 < p.p1 || p.p2 > kMaxP2) {
    error_ = "penalties must satisfy 0 <= p1 <= p2 <= 96 (the census cost's scale is 0..31)";
  } else if (p.uniqueness_percent < 0 || p.uniqueness_percent > 99) {
    error_ = "uniqueness_percent must be in 0..99";
  } else if (p.speckle_window < 0 || p.speckle_range < 0) {
    error_ = "speckle_window and speckle_range must not be negative";
  }
  if (error_ != nullptr) return;
  max_width_ = max_width / p.downscale;
  max_height_ = max_height / p.downscale;
  disparities_ = p.disparities / p.downscale;
  if (static_cast<long long>(max_width_) * max_height_ * disparities_ > kMaxCells) {
    error_ = "the image size times the disparities is too large a cost volume (over 2^30 cells): downscale";
    return;
  }
  ws_ = std::make_unique<Workspace>(max_width_, max_height_, disparities_, p.downscale == 2);
}

SemiGlobalMatcher::~SemiGlobalMatcher() = default;

DisparityStatus SemiGlobalMatcher::compute(const GreyView& left, const GreyView& right,
                                           const DisparityImage& out) noexcept {
  if (!valid()) return DisparityStatus::kNotConstructed;
  if (!left.valid() || !right.valid() || !out.valid()) return DisparityStatus::kBadImage;
  if (left.width != right.width || left.height != right.height || out.width != output_width(left.width) ||
      out.height != output_height(left.height)) {
    return DisparityStatus::kSizeMismatch;
  }
  const int w = output_width(left.width), h = output_height(left.height);
  if (w > max_width_ || h > max_height_) return DisparityStatus::kLargerThanWorkspace;
  if (disparities_ >= w) return DisparityStatus::kRangeTooWide;
  match(left, right, out);
  return DisparityStatus::kOk;
}

template <class B, int kPaths, bool kFused>
void SemiGlobalMatcher::aggregate(int w, int h) noexcept {
  constexpr int kN = kPaths / 2;  // paths per pass
  using W = typename B::Wide;
  Workspace& ws = *ws_;
  const int d = disparities_, slot = ws.slot;
  const typename B::V p1 = B::splat(static_cast<std::uint8_t>(params_.p1));
  const typename B::V jump = B::splat(static_cast<std::uint8_t>(params_.p2));
  const std::ptrdiff_t pixel = d, row_cells = static_cast<std::ptrdiff_t>(w) * d;
  // Direction j of a pass: 0 along the row, 1 along the column, 2 and 3
  // the diagonals; the column and diagonal paths keep their previous row.
  std::uint8_t* prev_row[3] = {ws.rows[0], ws.rows[1], ws.rows[2]};
  std::uint8_t* cur_row[3] = {ws.rows[3], ws.rows[4], ws.rows[5]};
  auto at = [slot](std::uint8_t* row, int x) { return row + static_cast<std::ptrdiff_t>(x) * slot; };

  const std::uint8_t* prev[4];
  std::uint8_t* cur[4];
  // With 4 paths the downward sums are bytes, in the first half of the
  // 16-bit volume's memory.
  std::uint8_t* pair_sums = reinterpret_cast<std::uint8_t*>(ws.sums.get());

  // Down: from the left, from above, from above left and above right. A
  // row's costs are computed just before it, so the pass finds them in cache.
  for (int y = 0; y < h; ++y) {
    census_costs(y, w);
    const std::uint8_t* cost = ws.cost.get() + y * row_cells;
    std::int16_t* sum = ws.sums.get() + y * row_cells;
    std::uint8_t* pair_sum = pair_sums + y * row_cells;
    for (int x = 0; x < w; ++x) {
      prev[0] = x > 0 ? ws.horizontal[(x - 1) & 1] : ws.zero;
      cur[0] = ws.horizontal[x & 1];
      prev[1] = y > 0 ? at(prev_row[0], x) : ws.zero;
      cur[1] = at(cur_row[0], x);
      if (kN == 4) {
        prev[2] = y > 0 && x > 0 ? at(prev_row[1], x - 1) : ws.zero;
        cur[2] = at(cur_row[1], x);
        prev[3] = y > 0 && x + 1 < w ? at(prev_row[2], x + 1) : ws.zero;
        cur[3] = at(cur_row[2], x);
      }
      down_paths<B, kN>(prev, cur, cost + x * pixel, sum + x * pixel, pair_sum + x * pixel, d, p1, jump);
    }
    std::swap(prev_row, cur_row);
  }

  // Up: from the right, from below, from below right and below left; each
  // pixel's sums are then complete and its disparity is chosen (fused:
  // from a one-pixel buffer in L1, packed_winner.hpp; else from the
  // volume, row by row).
  const DisparityRowScratch scratch{ws.left_best.get(), ws.right_best.get(), ws.right_cost.get()};
  std::int16_t* total = ws.total.get();
  std::int16_t* row_sums = ws.row_sums.get();
  for (int y = h - 1; y >= 0; --y) {
    const std::uint8_t* cost = ws.cost.get() + y * row_cells;
    const std::int16_t* sum = ws.sums.get() + y * row_cells;
    const std::uint8_t* pair_sum = pair_sums + y * row_cells;
    std::int16_t* out = ws.disparity.row(y);
    PackedWinner<W> winner(w, d, params_.uniqueness_percent, scratch.right_cost);
    for (int x = w - 1; x >= 0; --x) {
      prev[0] = x + 1 < w ? ws.horizontal[(x + 1) & 1] : ws.zero;
      cur[0] = ws.horizontal[x & 1];
      prev[1] = y + 1 < h ? at(prev_row[0], x) : ws.zero;
      cur[1] = at(cur_row[0], x);
      if (kN == 4) {
        prev[2] = y + 1 < h && x + 1 < w ? at(prev_row[1], x + 1) : ws.zero;
        cur[2] = at(cur_row[1], x);
        prev[3] = y + 1 < h && x > 0 ? at(prev_row[2], x - 1) : ws.zero;
        cur[3] = at(cur_row[2], x);
      }
      const std::int16_t* s = sum + x * pixel;
      const std::uint8_t* ps = pair_sum + x * pixel;
      if (kFused) {
        // The sums wait in a one-pixel buffer that stays in L1 rather than
        // in registers: the paths already use nearly all of them.
        up_paths<B, kN>(prev, cur, cost + x * pixel, s, ps, total, d, p1, jump);
        winner.begin(x);
        for (int k = 0; k < d; k += 8) winner.add(k, W::load(total + k));
        winner.finish(total, out + x, scratch.left_best + x);
      } else {
        up_paths<B, kN>(prev, cur, cost + x * pixel, s, ps, row_sums + x * pixel, d, p1, jump);
      }
    }
    std::swap(prev_row, cur_row);
    if (kFused) {
      winner.check_right(scratch.left_best, params_.lr_max_diff, out);
    } else {
      select_disparity_row(row_sums, w, d, params_.uniqueness_percent, params_.lr_max_diff, scratch, out);
    }
  }
}

void SemiGlobalMatcher::census_costs(int y, int w) noexcept {
  Workspace& ws = *ws_;
  const std::uint8_t* left_planes[kCensusPlanes];
  const std::uint8_t* right_planes[kCensusPlanes];
  for (int g = 0; g < kCensusPlanes; ++g) {
    left_planes[g] = ws.census_left[g].row(y);
    const std::uint8_t* r = ws.census_right[g].row(y);
    std::uint8_t* rev = ws.right_reversed.get() + static_cast<std::ptrdiff_t>(g) * ws.reversed_stride;
    for (int x = 0; x < w; ++x) rev[w - 1 - x] = r[x];
    right_planes[g] = rev;
  }
  census_cost_row(left_planes, right_planes, w, disparities_,
                  ws.cost.get() + static_cast<std::ptrdiff_t>(y) * w * disparities_);
}

void SemiGlobalMatcher::match(const GreyView& left_in, const GreyView& right_in, const DisparityImage& out) noexcept {
  Workspace& ws = *ws_;
  const int w = output_width(left_in.width), h = output_height(left_in.height), d = disparities_;
  GreyView left = left_in, right = right_in;
  if (params_.downscale == 2) {
    FeatureFilters::halve(left_in, ws.half_left);
    FeatureFilters::halve(right_in, ws.half_right);
    left = GreyView{ws.half_left.row(0), w, h, ws.half_left.stride()};
    right = GreyView{ws.half_right.row(0), w, h, ws.half_right.stride()};
  }
  census_transform_9x7(left, ws.census_left);
  census_transform_9x7(right, ws.census_right);

  // Sums are at most paths * (P2 + the largest cost): see kMaxP2.
  const bool fused = packed_winner_fits(params_.paths * (params_.p2 + kCensusBits), d);
  if (params_.paths == 8) {
    fused ? aggregate<simd::NativeU8, 8, true>(w, h) : aggregate<simd::NativeU8, 8, false>(w, h);
  } else {
    fused ? aggregate<simd::NativeU8, 4, true>(w, h) : aggregate<simd::NativeU8, 4, false>(w, h);
  }

  // The census window's margin repeats border pixels: no estimate there.
  for (int y = 0; y < h; ++y) {
    std::int16_t* row = ws.disparity.row(y);
    if (y < kCensusHalfHeight || y >= h - kCensusHalfHeight) {
      std::fill(row, row + w, std::int16_t{-1});
      continue;
    }
    for (int x = 0; x < std::min(kCensusHalfWidth, w); ++x) row[x] = -1;
    for (int x = std::max(0, w - kCensusHalfWidth); x < w; ++x) row[x] = -1;
  }
  if (params_.speckle_window > 0) {
    ws.speckles.filter(ws.disparity.row(0), w, h, ws.disparity.stride(), params_.speckle_window,
                       params_.speckle_range * kDisparityScale);
  }
  int valid = 0;
  for (int y = 0; y < h; ++y) {
    const std::int16_t* src = ws.disparity.row(y);
    std::uint16_t* dst = out.row(y);
    for (int x = 0; x < w; ++x) {
      const int v = src[x];
      valid += v >= 0 ? 1 : 0;
      dst[x] = v >= 0 ? static_cast<std::uint16_t>(v * params_.downscale) : kInvalidDisparity;
    }
  }
  valid_pixels_ = valid;
}

}  // namespace rtfuse::vision
