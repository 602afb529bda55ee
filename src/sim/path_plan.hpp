#pragma once
// The planar motion a scenario's [[path]] describes, planned once at
// construction so that any instant can be looked up in O(log n) without
// allocating, from any thread.
//
// Geometry and timing are planned apart, as a real path follower does:
//  - the path is a chain of pieces whose curvature is linear in arc length
//    (lines, arcs, and clothoids joining pieces of different curvature so
//    the yaw rate never steps) or sinusoidal (the figure eight, which then
//    closes exactly: its heading swings by the first zero of J0 either way);
//  - the speed along it is the fastest profile that keeps |dv/dt| within
//    max_accel, each segment's cruise speed, and rest at the start, the end
//    and around every spin and stop;
//  - spins turn in place with |yaw acceleration| within max_yaw_accel.
// The yaw acceleration is also within max_yaw_accel through clothoids at
// speed; on an arc ω = v/r, so speeding up on it adds a/r.
//
// Positions are integrated along the path with Gauss-Legendre quadrature
// from knots every few centimetres, so a lookup costs a few trig calls.
#include <string>
#include <utility>
#include <vector>

#include "sim/drive_scenario.hpp"

namespace rtfuse::sim {

// The base_link origin at one instant, in the odom frame (start: origin,
// facing +x). heading is unwrapped (the integral of the yaw rate).
struct PathPoint {
  double x = 0.0, y = 0.0, heading = 0.0;
  double speed = 0.0;      // forward, m/s
  double yaw_rate = 0.0;   // rad/s
  double accel = 0.0;      // dv/dt, m/s^2
  double yaw_accel = 0.0;  // rad/s^2
  double distance = 0.0;   // path length driven so far, m
};

// Why a scenario cannot be driven: the [[path]] entry (index; -1 for the
// whole drive) and the reason with the likely fix.
struct PlanProblem {
  int segment = -1;
  std::string message;
};

namespace plan_detail {

// A stretch of path, parameterised by its own arc length u in [0, length].
struct Piece {
  bool sinusoid = false;  // else clothoid: curvature k0 + k1 u (k1 = 0: line or arc)
  double s0 = 0.0;        // path length at its start
  double length = 0.0;
  double x0 = 0.0, y0 = 0.0, psi0 = 0.0;
  double k0 = 0.0, k1 = 0.0;
  double amp = 0.0, wave = 0.0;  // sinusoid: heading psi0 + amp (1 - cos(wave u))
  int knot0 = 0;  // position knots at u = i * kKnotStep (the last one at length)
  int knots = 1;

  double heading(double u) const noexcept;
  double curvature(double u) const noexcept;
  double curvature_slope(double u) const noexcept;  // d curvature / d u
};

// A stretch of time with constant acceleration: along a piece (move), or in
// place (turn: constant yaw acceleration; rest: nothing moves).
struct Phase {
  enum class Kind : unsigned char { kMove, kTurn, kRest };
  Kind kind = Kind::kRest;
  double t0 = 0.0, duration = 0.0;
  int piece = -1;                   // move
  double u0 = 0.0, v0 = 0.0, a = 0.0;  // move: start along the piece, speed, acceleration
  double x = 0.0, y = 0.0, s = 0.0;    // turn, rest: where
  double psi0 = 0.0, w0 = 0.0, alpha = 0.0;  // turn, rest: heading, yaw rate, yaw acceleration
};

}  // namespace plan_detail

class PathPlan {
 public:
  PathPlan() = default;  // at rest at the origin forever

  // False (plan left at rest) when a segment cannot be driven within the
  // limits, e.g. an arc too short for the curvature transitions it needs.
  static bool build(const DriveScenario& scenario, PathPlan* out, PlanProblem* problem);

  // t in seconds since the drive started; before it the robot rests at the
  // origin, after end_time() at its final pose.
  PathPoint at(double t) const noexcept;
  double end_time() const noexcept { return end_time_; }
  double length() const noexcept { return length_; }
  // Heading change over the whole drive (the sum of the arcs and spins).
  double final_heading() const noexcept { return final_heading_; }

  // Tightest curvature on the path, 1/m (tests bound the yaw acceleration by it).
  double max_curvature() const noexcept { return max_curvature_; }

 private:
  friend class PlanBuilder;
  using Piece = plan_detail::Piece;
  using Phase = plan_detail::Phase;

  std::pair<double, double> position(const Piece& p, double u) const noexcept;

  std::vector<Piece> pieces_;
  std::vector<Phase> phases_;
  std::vector<double> phase_start_;  // phases_[i].t0, for the binary search
  std::vector<double> knot_x_;
  std::vector<double> knot_y_;
  double end_time_ = 0.0;
  double length_ = 0.0;
  double final_heading_ = 0.0;
  double max_curvature_ = 0.0;
  PathPoint final_{};
};

}  // namespace rtfuse::sim
