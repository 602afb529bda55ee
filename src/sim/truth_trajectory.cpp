#include "sim/truth_trajectory.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/angles.hpp"

namespace rtfuse::sim {

TruthSource::~TruthSource() = default;

TruthTrajectory::TruthTrajectory(const DriveScenario& sc) {
  valid_ = PathPlan::build(sc, &plan_, &problem_);
  duration_s_ = sc.duration_s > 0.0 ? sc.duration_s : plan_.end_time();
  wheel_count_ = std::clamp(sc.robot.wheel_count, 0, kMaxSimWheels);
  track_width_ = sc.robot.track_width_m;
  for (int w = 0; w < wheel_count_; ++w) wheel_left_[w] = sc.robot.wheels[static_cast<std::size_t>(w)].left;

  // The noise over the path; afterwards the robot stands and slips nothing.
  slip_ = WheelSlipModel(sc, plan_.end_time());
  if (slip_.has_noise()) {
    const std::size_t n = slip_.knot_count();
    const double step = slip_.noise_step();
    std::vector<double> side_speed[2];
    for (auto& v : side_speed) v.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const PathPoint p = plan_.at(static_cast<double>(k) * step);
      side_speed[0][k] = p.speed - 0.5 * track_width_ * p.yaw_rate;
      side_speed[1][k] = p.speed + 0.5 * track_width_ * p.yaw_rate;
    }
    for (int w = 0; w < wheel_count_; ++w) {
      const std::vector<double>& speed = side_speed[wheel_left_[w] ? 0 : 1];
      rate_[w].resize(n);
      rolled_[w].resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        rate_[w][k] = speed[k] * slip_.knot(w, k);
        rolled_[w][k] = k == 0 ? 0.0 : rolled_[w][k - 1] + 0.5 * step * (rate_[w][k - 1] + rate_[w][k]);
      }
    }
  }

  for (int i = 0; i < slip_.episode_count(); ++i) {
    const WheelSlipModel::Episode& e = slip_.episode(i);
    const PathPoint a = plan_.at(e.start);
    const PathPoint b = plan_.at(e.end);
    for (int side = 0; side < 2; ++side) {
      episode_sides_[i].at_start[side] = side_distance(a, side == 0);
      episode_sides_[i].at_end[side] = side_distance(b, side == 0);
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
  if (!slip_.has_noise()) {
    *integral = 0.0;
    return 0.0;
  }
  std::size_t k = 0;
  double dt = 0.0;
  slip_.locate(t, &k, &dt);
  const double fraction = slip_.noise_at(wheel, k, dt);
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
    for (int i = 0; i < slip_.episode_count(); ++i) {
      const WheelSlipModel::Episode& e = slip_.episode(i);
      if ((e.wheel_mask & (1u << w)) == 0 || !(t_s > e.start)) continue;
      const int side = left ? 0 : 1;
      const double now = t_s < e.end ? ground : episode_sides_[i].at_end[side];
      slipped += e.fraction * (now - episode_sides_[i].at_start[side]);
      if (t_s < e.end) fraction += e.fraction;
    }
    s.wheel_distance[w] = ground + slipped;
    s.wheel_slip[w] = fraction;
  }
  return s;
}

TruthState TruthTrajectory::truth_at(double t_s) noexcept {
  return static_cast<const TruthTrajectory&>(*this).truth_at(t_s);
}

}  // namespace rtfuse::sim
