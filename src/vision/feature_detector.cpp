#include "vision/feature_detector.hpp"

#include <algorithm>

namespace rtfuse::vision {
namespace {

// The 16 sample points, (du, dv) each: a ring and a cross around the
// feature that covers an 11 x 11 window sparsely.
constexpr int kSamples[16][2] = {{-3, -1}, {-3, 1}, {-1, -1}, {-1, 1}, {3, -1}, {3, 1}, {1, -1}, {1, 1},
                                 {-1, -5}, {-1, 5}, {1, -5},  {1, 5},  {-5, -3}, {-5, 3}, {5, -3}, {5, 3}};

}  // namespace

int max_features(int width, int height, const SuppressionParams& p) noexcept {
  const int first = p.n + p.margin;
  const int step = p.n + 1;
  const int cols = width - p.n - p.margin > first ? (width - p.n - p.margin - first + step - 1) / step : 0;
  const int rows = height - p.n - p.margin > first ? (height - p.n - p.margin - first + step - 1) / step : 0;
  return cols * rows * kFeatureClasses;
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
