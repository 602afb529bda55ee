// Block non-maximum suppression (declared in vision/feature_detector.hpp),
// in eight-lane integer vectors and without data-dependent branches: it was
// the largest share of a frame when written pixel by pixel with a branch
// per class, most of them mispredicted.
//
// Three facts make it so without changing a single feature:
//  - a block's first extreme pixel in row-major order is, among the columns
//    reaching the block's extreme, the one whose first extreme row is the
//    least (ties: the leftmost column); the columns' extremes and first rows
//    come from a vertical pass over the block's rows;
//  - that choice is the largest of one integer key per column, the value
//    (negated for a minimum) above the row's distance from the bottom;
//  - nothing inside the block beats its own extreme, so "nothing outside
//    the block beats it" is "nothing in the whole window beats it", one
//    compare per eight pixels of each window row.
#include <algorithm>
#include <climits>

#include "vision/feature_detector.hpp"
#include "vision/simd_i16.hpp"

namespace rtfuse::vision {
namespace {

// Columns per pass over a block row: whole blocks, a multiple of 8 lanes
// of room on the stack.
constexpr int kChunk = 64;

struct Extremum {
  int u = 0, v = 0;
  int value = 0;
};

// Whether some pixel of r in rows [v0, v1], columns [u0, u1] is strictly
// beyond value in direction kSign (+1 above, -1 below). Every row is read
// (no early exit): a mispredicted exit cost more than the rest of the rows.
template <class S, int kSign>
bool beaten(const Plane<std::int16_t>& r, int value, int u0, int u1, int v0, int v1) noexcept {
  const typename S::V limit = S::splat(value);
  auto beyond = [&](typename S::V x) { return S::bits(kSign > 0 ? S::gt(x, limit) : S::gt(limit, x)); };
  auto extreme = [](typename S::V a, typename S::V b) { return kSign > 0 ? S::max(a, b) : S::min(a, b); };
  const int w = r.width();
  // The usual window (n <= 3) is one vector wide: the rows' extreme, then
  // one compare.
  if (u1 - u0 < 8 && u0 + 8 <= w) {
    typename S::V acc = S::load(r.row(v0) + u0);
    for (int v = v0 + 1; v <= v1; ++v) acc = extreme(acc, S::load(r.row(v) + u0));
    return (beyond(acc) & ((1u << (u1 - u0 + 1)) - 1u)) != 0;
  }
  unsigned hits = 0;
  for (int v = v0; v <= v1; ++v) {
    const std::int16_t* row = r.row(v);
    for (int c = u0; c <= u1; c += 8) {
      const int lanes = std::min(8, u1 - c + 1);
      if (c + 8 <= w) {
        hits |= beyond(S::load(row + c)) & ((1u << lanes) - 1u);
      } else {
        for (int u = c; u < c + lanes; ++u) hits |= kSign * row[u] > kSign * value ? 1u : 0u;
      }
    }
  }
  return hits != 0;
}

// Per column of [c0, c0 + count) over rows [v0, v1]: the largest and least
// response and the first row reaching each (vertical pass).
template <class S>
void column_extremes(const Plane<std::int16_t>& r, int c0, int count, int v0, int v1, std::int16_t* hi,
                     std::int16_t* hi_row, std::int16_t* lo, std::int16_t* lo_row) noexcept {
  const int w = r.width();
  int c = 0;
  for (; c + 8 <= count && c0 + c + 8 <= w; c += 8) {
    typename S::V mx = S::load(r.row(v0) + c0 + c), mn = mx;
    typename S::V mx_row = S::splat(v0), mn_row = mx_row;
    for (int v = v0 + 1; v <= v1; ++v) {
      const typename S::V x = S::load(r.row(v) + c0 + c);
      const typename S::V row = S::splat(v);
      // Strictly beyond: an equal value keeps the earlier row.
      mx_row = S::select(S::gt(x, mx), row, mx_row);
      mn_row = S::select(S::gt(mn, x), row, mn_row);
      mx = S::max(mx, x);
      mn = S::min(mn, x);
    }
    S::store(hi + c, mx);
    S::store(hi_row + c, mx_row);
    S::store(lo + c, mn);
    S::store(lo_row + c, mn_row);
  }
  for (; c < count; ++c) {
    const int u = c0 + c;
    int mx = r.row(v0)[u], mn = mx, mx_row = v0, mn_row = v0;
    for (int v = v0 + 1; v <= v1; ++v) {
      const int x = r.row(v)[u];
      if (x > mx) mx = x, mx_row = v;
      if (x < mn) mn = x, mn_row = v;
    }
    hi[c] = static_cast<std::int16_t>(mx);
    hi_row[c] = static_cast<std::int16_t>(mx_row);
    lo[c] = static_cast<std::int16_t>(mn);
    lo_row[c] = static_cast<std::int16_t>(mn_row);
  }
}

// The block's first extreme pixel from its columns' extremes (columns
// [c, c + width) of the pass, block rows from v0, at most 64 of them): the
// largest key, the first column on a tie.
Extremum block_extremum(const std::int16_t* value, const std::int16_t* row, int bu, int c, int width, int v0,
                        int sign) noexcept {
  int best = INT_MIN, at = 0;
  for (int i = 0; i < width; ++i) {
    const int key = sign * value[c + i] * 256 + (255 - (row[c + i] - v0));
    at = key > best ? i : at;
    best = key > best ? key : best;
  }
  return {bu + at, row[c + at], value[c + at]};
}

template <class S>
int suppress(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner, const SuppressionParams& p,
             Feature* out, int capacity, int* dropped) noexcept {
  const int w = blob.width(), h = blob.height();
  const int n = p.n;
  const int umax = w - 1 - p.margin, vmax = h - 1 - p.margin;
  const int step = n + 1;
  int count = 0;
  int lost = 0;
  if (n < 0 || step > kChunk) {  // outside what the buffers and keys hold
    if (dropped != nullptr) *dropped = 0;
    return 0;
  }
  const int blocks_per_pass = kChunk / step;
  std::int16_t buf[8][kChunk + 8];
  const int first = n + p.margin;
  for (int bv = first; bv < h - n - p.margin; bv += step) {
    // Blocks never reach past umax, vmax: bu + n < w - margin.
    for (int bu0 = first; bu0 < w - n - p.margin; bu0 += blocks_per_pass * step) {
      const int blocks = std::min(blocks_per_pass, (w - n - p.margin - bu0 + step - 1) / step);
      const int cols = blocks * step;
      column_extremes<S>(blob, bu0, cols, bv, bv + n, buf[0], buf[1], buf[2], buf[3]);
      column_extremes<S>(corner, bu0, cols, bv, bv + n, buf[4], buf[5], buf[6], buf[7]);
      for (int b = 0; b < blocks; ++b) {
        const int c = b * step, bu = bu0 + c;
        // FeatureClass order: blob min, blob max, corner min, corner max.
        const Extremum e[kFeatureClasses] = {
            block_extremum(buf[2], buf[3], bu, c, step, bv, -1), block_extremum(buf[0], buf[1], bu, c, step, bv, 1),
            block_extremum(buf[6], buf[7], bu, c, step, bv, -1), block_extremum(buf[4], buf[5], bu, c, step, bv, 1)};
        for (int k = 0; k < kFeatureClasses; ++k) {
          const int sign = (k == kBlobMax || k == kCornerMax) ? 1 : -1;
          const bool strong = sign * e[k].value >= p.tau;
          const Plane<std::int16_t>& r = k < 2 ? blob : corner;
          const int u0 = std::max(0, e[k].u - n), u1 = std::min(umax, e[k].u + n);
          const int v0 = std::max(0, e[k].v - n), v1 = std::min(vmax, e[k].v + n);
          const bool kept = strong & !(sign > 0 ? beaten<S, 1>(r, e[k].value, u0, u1, v0, v1)
                                                : beaten<S, -1>(r, e[k].value, u0, u1, v0, v1));
          if (count < capacity) {
            // Written whether kept or not; only a kept one is counted.
            Feature& f = out[count];
            f.u = e[k].u;
            f.v = e[k].v;
            f.value = static_cast<std::int16_t>(e[k].value);
            f.cls = static_cast<std::uint8_t>(k);
            count += kept ? 1 : 0;
          } else {
            lost += kept ? 1 : 0;
          }
        }
      }
    }
  }
  if (dropped != nullptr) *dropped = lost;
  return count;
}

}  // namespace

int suppress_non_maxima(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner, const SuppressionParams& p,
                        Feature* out, int capacity, int* dropped) noexcept {
  return suppress<simd::NativeI16>(blob, corner, p, out, capacity, dropped);
}

int suppress_non_maxima_plain(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner,
                              const SuppressionParams& p, Feature* out, int capacity, int* dropped) noexcept {
  return suppress<simd::PlainI16>(blob, corner, p, out, capacity, dropped);
}

}  // namespace rtfuse::vision
