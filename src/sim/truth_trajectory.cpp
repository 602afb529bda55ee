#include "sim/truth_trajectory.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/angles.hpp"
#include "sim/counter_rng.hpp"

namespace rtfuse::sim {

namespace {
// Slip changes over tenths of a second; 10 ms knots resolve that, and a
// long run widens the step rather than grow the tables without bound.
constexpr double kSlipStep = 0.01;
constexpr std::size_t kMaxSlipKnots = std::size_t{1} << 18;  // 44 min at 10 ms
}  // namespace

TruthTrajectory::TruthTrajectory(const DriveScenario& sc) {
  valid_ = PathPlan::build(sc, &plan_, &problem_);
  duration_s_ = sc.duration_s > 0.0 ? sc.duration_s : plan_.end_time();
  wheel_count_ = std::clamp(sc.robot.wheel_count, 0, kMaxSimWheels);
  track_width_ = sc.robot.track_width_m;
  for (int w = 0; w < wheel_count_; ++w) wheel_left_[w] = sc.robot.wheels[static_cast<std::size_t>(w)].left;

  const double end = plan_.end_time();
  const double sigma = sc.slip.noise_fraction;
  const double tau = sc.slip.correlation_time_s;
  if (sigma > 0.0 && std::isfinite(sigma) && tau > 0.0 && end > 0.0) {
    noise_step_ = std::max(kSlipStep, end / static_cast<double>(kMaxSlipKnots - 2));
    const auto n = static_cast<std::size_t>(std::ceil(end / noise_step_)) + 2;
    // First-order Gauss-Markov, started in its stationary distribution.
    const double a = std::exp(-noise_step_ / tau);
    const double b = sigma * std::sqrt(1.0 - a * a);
    std::vector<double> side_speed[2];
    for (auto& v : side_speed) v.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const PathPoint p = plan_.at(static_cast<double>(k) * noise_step_);
      side_speed[0][k] = p.speed - 0.5 * track_width_ * p.yaw_rate;
      side_speed[1][k] = p.speed + 0.5 * track_width_ * p.yaw_rate;
    }
    for (int w = 0; w < wheel_count_; ++w) {
      const std::uint64_t stream = stream::kWheelSlip + static_cast<std::uint64_t>(w);
      const std::vector<double>& speed = side_speed[wheel_left_[w] ? 0 : 1];
      noise_[w].resize(n);
      rate_[w].resize(n);
      rolled_[w].resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        const double white = counter_normal(sc.seed, stream, k);
        noise_[w][k] = k == 0 ? sigma * white : a * noise_[w][k - 1] + b * white;
        rate_[w][k] = speed[k] * noise_[w][k];
        rolled_[w][k] = k == 0 ? 0.0 : rolled_[w][k - 1] + 0.5 * noise_step_ * (rate_[w][k - 1] + rate_[w][k]);
      }
    }
  }

  episode_count_ = std::clamp(sc.slip.episode_count, 0, kMaxSlipEpisodes);
  for (int i = 0; i < episode_count_; ++i) {
    const SlipEpisode& in = sc.slip.episodes[static_cast<std::size_t>(i)];
    Episode& e = episodes_[i];
    e.start = in.start_s;
    e.end = in.start_s + in.duration_s;
    e.fraction = in.fraction;
    e.wheel_mask = in.wheel_mask;
    const PathPoint a = plan_.at(e.start);
    const PathPoint b = plan_.at(e.end);
    for (int side = 0; side < 2; ++side) {
      e.side_at_start[side] = side_distance(a, side == 0);
      e.side_at_end[side] = side_distance(b, side == 0);
    }
  }
}

double TruthTrajectory::side_distance(const PathPoint& p, bool left) const noexcept {
  const double turn = 0.5 * track_width_ * p.heading;
  return left ? p.distance - turn : p.distance + turn;
}

// The continuous slip fraction of `wheel` at t, and in *integral the slip
// distance it has added since the start.
double TruthTrajectory::slip_noise(int wheel, double t, double* integral, const PathPoint& p) const noexcept {
  const std::vector<double>& noise = noise_[wheel];
  if (noise.size() < 2) {
    *integral = 0.0;
    return 0.0;
  }
  const double tc = t > 0.0 ? std::min(t, plan_.end_time()) : 0.0;  // NaN: the start
  const std::size_t k = std::min(static_cast<std::size_t>(tc / noise_step_), noise.size() - 2);
  const double dt = tc - static_cast<double>(k) * noise_step_;
  const double fraction = noise[k] + (noise[k + 1] - noise[k]) * (dt / noise_step_);
  const double side_speed = p.speed + (wheel_left_[wheel] ? -0.5 : 0.5) * track_width_ * p.yaw_rate;
  *integral = rolled_[wheel][k] + 0.5 * dt * (rate_[wheel][k] + side_speed * fraction);
  return fraction;
}

TruthState TruthTrajectory::truth_at(double t_s) const noexcept {
  TruthState s;
  s.t = t_s;
  const PathPoint p = plan_.at(t_s);
  s.x = p.x;
  s.y = p.y;
  s.heading = p.heading;
  s.yaw = geometry::wrap_angle(p.heading);
  s.speed = p.speed;
  s.yaw_rate = p.yaw_rate;
  s.yaw_accel = p.yaw_accel;
  s.accel_body[0] = p.accel;
  s.accel_body[1] = p.speed * p.yaw_rate;
  s.accel_body[2] = 0.0;
  s.distance = p.distance;
  s.wheel_count = wheel_count_;
  for (int w = 0; w < wheel_count_; ++w) {
    const bool left = wheel_left_[w];
    const double ground = side_distance(p, left);
    double slipped = 0.0;
    double fraction = slip_noise(w, t_s, &slipped, p);
    for (int i = 0; i < episode_count_; ++i) {
      const Episode& e = episodes_[i];
      if ((e.wheel_mask & (1u << w)) == 0 || !(t_s > e.start)) continue;
      const int side = left ? 0 : 1;
      const double now = t_s < e.end ? ground : e.side_at_end[side];
      slipped += e.fraction * (now - e.side_at_start[side]);
      if (t_s < e.end) fraction += e.fraction;
    }
    s.wheel_distance[w] = ground + slipped;
    s.wheel_slip[w] = fraction;
  }
  return s;
}

}  // namespace rtfuse::sim
