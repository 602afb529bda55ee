#pragma once
// Ground truth of a drive as a pure function of time: the planar motion of
// base_link (path_plan.hpp) and, per wheel, the distance its tread has
// rolled, slip included. The encoder counts are this distance through the
// true wheel radius, so they are exact integrals of the motion:
//
//   left  = integral of (v - yaw_rate * track / 2) dt + slip
//   right = integral of (v + yaw_rate * track / 2) dt + slip
//
// Slip is wheel against ground (the robot's true motion is the plan; the
// wheel turns more, or less, than that motion needs): a continuous
// Gauss-Markov fraction per wheel, precomputed at construction from
// counter-based noise, plus the scenario's episodes.
//
// truth_at() is deterministic, thread-safe (const, no shared mutable state),
// allocation-free and O(log n): the loop thread and the IMU thread both call it.
#include <vector>

#include "sim/drive_scenario.hpp"
#include "sim/path_plan.hpp"

namespace rtfuse::sim {

struct TruthState {
  double t = 0.0;  // s since the drive started
  // base_link in odom (flat floor: z, roll, pitch are 0).
  double x = 0.0, y = 0.0;
  double yaw = 0.0;          // wrapped to [-pi, pi)
  double heading = 0.0;      // unwrapped: the integral of yaw_rate from the start
  double speed = 0.0;        // forward, m/s
  double yaw_rate = 0.0;     // rad/s
  double yaw_accel = 0.0;    // rad/s^2
  // Acceleration of the base_link origin in base_link axes: forward dv/dt,
  // centripetal v * yaw_rate towards the inside of the turn, 0 up (gravity
  // is the IMU's business).
  double accel_body[3] = {0.0, 0.0, 0.0};
  double distance = 0.0;     // path length driven, m
  int wheel_count = 0;
  double wheel_distance[kMaxSimWheels] = {};  // rolled, slip included, m (forward positive)
  double wheel_slip[kMaxSimWheels] = {};      // current slip fraction per wheel
};

class TruthTrajectory {
 public:
  // The scenario must have loaded (load_drive_scenario); one that cannot be
  // planned leaves the robot at rest at the origin and valid() false.
  explicit TruthTrajectory(const DriveScenario& scenario);

  TruthState truth_at(double t_s) const noexcept;

  bool valid() const noexcept { return valid_; }
  const PlanProblem& problem() const noexcept { return problem_; }
  const PathPlan& plan() const noexcept { return plan_; }
  // The run: the scenario's duration, else the path's.
  double duration_s() const noexcept { return duration_s_; }
  int wheel_count() const noexcept { return wheel_count_; }
  double track_width() const noexcept { return track_width_; }

 private:
  // Rolled distance of a side without slip: distance -/+ heading * track / 2.
  double side_distance(const PathPoint& p, bool left) const noexcept;
  double slip_noise(int wheel, double t, double* integral, const PathPoint& p) const noexcept;

  PathPlan plan_;
  PlanProblem problem_;
  bool valid_ = false;
  double duration_s_ = 0.0;
  int wheel_count_ = 0;
  double track_width_ = 0.0;
  bool wheel_left_[kMaxSimWheels] = {};

  // Continuous slip: per wheel, noise_[w][k] is the fraction at k * step,
  // rate_[w][k] the slip speed it causes then and rolled_[w][k] the slip
  // distance added by then (trapezoid rule, used the same way between knots
  // so a lookup and the table always agree at a knot).
  double noise_step_ = 0.01;
  std::vector<double> noise_[kMaxSimWheels];
  std::vector<double> rate_[kMaxSimWheels];
  std::vector<double> rolled_[kMaxSimWheels];

  struct Episode {
    double start = 0.0, end = 0.0, fraction = 0.0;
    std::uint8_t wheel_mask = 0;
    double side_at_start[2] = {0.0, 0.0};  // [left, right] side distance
    double side_at_end[2] = {0.0, 0.0};
  };
  int episode_count_ = 0;
  Episode episodes_[kMaxSlipEpisodes];
};

}  // namespace rtfuse::sim
