#pragma once
// Where a simulated device reads the robot's ground truth from. The robot
// gives each device its own source: a scripted drive shares one
// TruthTrajectory (a pure function of time, safe from any thread), a
// commanded drive gives every reader thread a CommandedTruth of its own
// (commanded_base.hpp), whose integration state is that thread's alone.
//
// truth_at() is not const: a source may advance its own state to answer.
// An instance therefore belongs to one thread unless its class says it is
// thread-safe (TruthTrajectory does).
#include "sim/drive_scenario.hpp"

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

class TruthSource {
 public:
  virtual ~TruthSource();
  // t_s: seconds since the drive started (the devices' t0). Never allocates.
  virtual TruthState truth_at(double t_s) noexcept = 0;

 protected:
  TruthSource() = default;
  TruthSource(const TruthSource&) = default;
  TruthSource& operator=(const TruthSource&) = default;
};

}  // namespace rtfuse::sim
