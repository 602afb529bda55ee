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
// allocation-free and O(log n): the loop thread and the IMU thread both call
// it, so the robot gives every device the same one as its TruthSource.
#include <vector>

#include "sim/drive_scenario.hpp"
#include "sim/path_plan.hpp"
#include "sim/truth_source.hpp"
#include "sim/wheel_slip_model.hpp"

namespace rtfuse::sim {

class TruthTrajectory final : public TruthSource {
 public:
  // The scenario must have loaded (load_drive_scenario); one that cannot be
  // planned leaves the robot at rest at the origin and valid() false.
  explicit TruthTrajectory(const DriveScenario& scenario);

  TruthState truth_at(double t_s) const noexcept;
  // TruthSource: the same, for a device that reads it as one.
  TruthState truth_at(double t_s) noexcept override;

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

  // Continuous slip: per wheel, rate_[w][k] is the slip speed the
  // fraction at knot k causes then and rolled_[w][k] the slip distance
  // added by then (trapezoid rule, used the same way between knots so a
  // lookup and the table always agree at a knot).
  WheelSlipModel slip_;
  std::vector<double> rate_[kMaxSimWheels];
  std::vector<double> rolled_[kMaxSimWheels];

  // The ground each side covers during an episode, from the plan.
  struct EpisodeSides {
    double at_start[2] = {0.0, 0.0};  // [left, right] side distance
    double at_end[2] = {0.0, 0.0};
  };
  EpisodeSides episode_sides_[kMaxSlipEpisodes];
};

}  // namespace rtfuse::sim
