#include "vision/circular_matcher.hpp"

#include <algorithm>
#include <climits>

namespace rtfuse::vision {
namespace {

// The best same-class feature of `target` in the window, or -1.
int best_match(const Feature& q, const FeatureIndex& target, int u0, int u1, int v0, int v1) noexcept {
  int best = -1;
  int best_cost = INT_MAX;
  target.for_each_in(q.cls, u0, u1, v0, v1, [&](int i) {
    const int cost = descriptor_sad(q.descriptor, target.features()[i].descriptor);
    if (cost < best_cost) {
      best_cost = cost;
      best = i;
    }
  });
  return best;
}

}  // namespace

CircularMatcher::CircularMatcher(int max_features)
    : capacity_(max_features), used_(new std::uint8_t[static_cast<std::size_t>(std::max(1, max_features))]()) {}

int CircularMatcher::match(const FeatureIndex& lp, const FeatureIndex& rp, const FeatureIndex& lc,
                           const FeatureIndex& rc, const MatchParams& p, const MotionPrediction* prediction,
                           CircularMatch* out, int capacity, const int* queries, int num_queries) noexcept {
  std::fill(used_.get(), used_.get() + std::min(lc.size(), capacity_), std::uint8_t{0});
  int n = 0;
  const int total = queries != nullptr ? num_queries : lp.size();
  for (int q = 0; q < total && n < capacity; ++q) {
    const int i = queries != nullptr ? queries[q] : q;
    const Feature& a = lp.features()[i];
    // Previous left -> previous right: same row, the right image sees it further left.
    const int j = best_match(a, rp, a.u - p.max_disparity, a.u, a.v - p.row_tolerance, a.v + p.row_tolerance);
    if (j < 0) continue;
    const Feature& b = rp.features()[j];
    int pu_r = b.u, pv_r = b.v, pu_l = a.u, pv_l = a.v;
    int radius = p.flow_radius;
    if (prediction != nullptr && prediction->predict(a.u, a.v, a.u - b.u, &pu_r, &pv_r, &pu_l, &pv_l)) {
      radius = p.predicted_radius;
    } else {
      pu_r = b.u, pv_r = b.v, pu_l = a.u, pv_l = a.v;
    }
    // Previous right -> current right: the motion.
    const int k = best_match(b, rc, pu_r - radius, pu_r + radius, pv_r - radius, pv_r + radius);
    if (k < 0) continue;
    const Feature& c = rc.features()[k];
    // Current right -> current left: same row, further right.
    const int l = best_match(c, lc, c.u, c.u + p.max_disparity, c.v - p.row_tolerance, c.v + p.row_tolerance);
    if (l < 0 || l >= capacity_ || used_[l]) continue;
    const Feature& d = lc.features()[l];
    // Current left -> previous left: back to where it started?
    const int back_u = prediction != nullptr && radius == p.predicted_radius ? d.u + (a.u - pu_l) : d.u;
    const int back_v = prediction != nullptr && radius == p.predicted_radius ? d.v + (a.v - pv_l) : d.v;
    const int m = best_match(d, lp, back_u - radius, back_u + radius, back_v - radius, back_v + radius);
    if (m != i) continue;
    used_[l] = 1;
    out[n++] = CircularMatch{i, j, l, k};
  }
  return n;
}

}  // namespace rtfuse::vision
