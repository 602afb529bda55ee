#include "vision/feature_detector.hpp"

#include <algorithm>

namespace rtfuse::vision {
namespace {

// The 16 sample points, (du, dv) each: a ring and a cross around the
// feature that covers an 11 x 11 window sparsely.
constexpr int kSamples[16][2] = {{-3, -1}, {-3, 1}, {-1, -1}, {-1, 1}, {3, -1}, {3, 1}, {1, -1}, {1, 1},
                                 {-1, -5}, {-1, 5}, {1, -5},  {1, 5},  {-5, -3}, {-5, 3}, {5, -3}, {5, 3}};

struct Extremum {
  int u = 0, v = 0;
  int value = 0;
};

// True when no pixel of the (2n+1)^2 window around e, outside the block
// [bu, bu+n] x [bv, bv+n], is strictly beyond e in the direction sign
// (+1 maximum, -1 minimum).
bool is_extremum(const Plane<std::int16_t>& r, const Extremum& e, int sign, int n, int bu, int bv, int umax,
                 int vmax) noexcept {
  const int u0 = std::max(0, e.u - n), u1 = std::min(umax, e.u + n);
  const int v0 = std::max(0, e.v - n), v1 = std::min(vmax, e.v + n);
  // Row by row; on the block's rows only the parts left and right of it.
  const int limit = sign * e.value;
  auto beaten = [&](const std::int16_t* row, int a, int b) {
    for (int u = a; u <= b; ++u) {
      if (sign * row[u] > limit) return true;
    }
    return false;
  };
  for (int v = v0; v <= v1; ++v) {
    const std::int16_t* row = r.row(v);
    if (v >= bv && v <= bv + n) {
      if (beaten(row, u0, std::min(u1, bu - 1)) || beaten(row, std::max(u0, bu + n + 1), u1)) return false;
    } else if (beaten(row, u0, u1)) {
      return false;
    }
  }
  return true;
}

}  // namespace

int max_features(int width, int height, const SuppressionParams& p) noexcept {
  const int first = p.n + p.margin;
  const int step = p.n + 1;
  const int cols = width - p.n - p.margin > first ? (width - p.n - p.margin - first + step - 1) / step : 0;
  const int rows = height - p.n - p.margin > first ? (height - p.n - p.margin - first + step - 1) / step : 0;
  return cols * rows * kFeatureClasses;
}

int suppress_non_maxima(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner,
                        const SuppressionParams& p, Feature* out, int capacity, int* dropped) noexcept {
  const int w = blob.width(), h = blob.height();
  const int n = p.n;
  const int umax = w - 1 - p.margin, vmax = h - 1 - p.margin;
  int count = 0;
  int lost = 0;
  for (int bv = n + p.margin; bv < h - n - p.margin; bv += n + 1) {
    for (int bu = n + p.margin; bu < w - n - p.margin; bu += n + 1) {
      Extremum e[kFeatureClasses];
      bool first = true;
      for (int v = bv; v <= std::min(bv + n, vmax); ++v) {
        const std::int16_t* b = blob.row(v);
        const std::int16_t* c = corner.row(v);
        for (int u = bu; u <= std::min(bu + n, umax); ++u) {
          if (first) {
            for (int k = 0; k < kFeatureClasses; ++k) e[k] = {u, v, k < 2 ? b[u] : c[u]};
            first = false;
            continue;
          }
          if (b[u] < e[kBlobMin].value) e[kBlobMin] = {u, v, b[u]};
          if (b[u] > e[kBlobMax].value) e[kBlobMax] = {u, v, b[u]};
          if (c[u] < e[kCornerMin].value) e[kCornerMin] = {u, v, c[u]};
          if (c[u] > e[kCornerMax].value) e[kCornerMax] = {u, v, c[u]};
        }
      }
      for (int k = 0; k < kFeatureClasses; ++k) {
        const int sign = (k == kBlobMax || k == kCornerMax) ? 1 : -1;
        if (sign * e[k].value < p.tau) continue;
        if (!is_extremum(k < 2 ? blob : corner, e[k], sign, n, bu, bv, umax, vmax)) continue;
        if (count == capacity) {
          ++lost;
          continue;
        }
        Feature& f = out[count++];
        f.u = e[k].u;
        f.v = e[k].v;
        f.value = static_cast<std::int16_t>(e[k].value);
        f.cls = static_cast<std::uint8_t>(k);
      }
    }
  }
  if (dropped != nullptr) *dropped = lost;
  return count;
}

void describe(const Plane<std::uint8_t>& du, const Plane<std::uint8_t>& dv, Feature* features, int count) noexcept {
  for (int i = 0; i < count; ++i) {
    Feature& f = features[i];
    for (int s = 0; s < 16; ++s) {
      const int u = f.u + kSamples[s][0], v = f.v + kSamples[s][1];
      f.descriptor[2 * s] = du.row(v)[u];
      f.descriptor[2 * s + 1] = dv.row(v)[u];
    }
  }
}

}  // namespace rtfuse::vision
