#pragma once
// Circular matching of features across two stereo pairs (Kitt, Geiger and
// Lategahn 2010): previous left -> previous right (along the row) ->
// current right (the motion) -> current left (along the row) -> previous
// left. A feature is kept only when the circle closes on itself, which
// rejects most wrong matches before any geometry is fitted.
//
// Each step takes, among the target image's features of the same class in
// a window, the one with the least descriptor SAD (ties: the first in the
// index's fixed order). The motion steps search either a window around the
// feature itself or, given a prediction (the previous motion applied to the
// point the previous pair triangulates), a smaller one around the predicted
// position. No allocation: the output array is the caller's.
#include <cstdint>
#include <memory>

#include "vision/feature_index.hpp"

namespace rtfuse::vision {

struct CircularMatch {
  int lp = -1, rp = -1, lc = -1, rc = -1;  // feature indices in the four images
};

struct MatchParams {
  int max_disparity = 128;   // pixels (of the features), previous and current pair alike
  int row_tolerance = 1;     // |v_left - v_right| on a rectified pair
  int flow_radius = 100;     // motion window without a prediction
  int predicted_radius = 10;  // motion window around a prediction
};

// Where a previous-left feature at (u, v) with disparity d should appear in
// the current right and left images; false when it cannot say (the point
// would be behind the camera).
class MotionPrediction {
 public:
  virtual ~MotionPrediction() = default;
  virtual bool predict(int u, int v, int disparity, int* u_right, int* v_right, int* u_left,
                       int* v_left) const noexcept = 0;
};

class CircularMatcher {
 public:
  // For images whose current-left feature arrays hold at most max_features.
  explicit CircularMatcher(int max_features);

  // Matches into out[0..capacity); returns the count. The circles start at
  // the previous-left features queries[0..num_queries) (null: all, in
  // order). A current-left feature closes at most one circle (the first).
  int match(const FeatureIndex& lp, const FeatureIndex& rp, const FeatureIndex& lc, const FeatureIndex& rc,
            const MatchParams& params, const MotionPrediction* prediction, CircularMatch* out, int capacity,
            const int* queries = nullptr, int num_queries = 0) noexcept;

 private:
  int capacity_;
  std::unique_ptr<std::uint8_t[]> used_;  // per current-left feature
};

}  // namespace rtfuse::vision
