#pragma once
// The LCM-level simulated robot of config/sim_lcm.toml: a figure-eight drive with ground
// truth, producing the encoded LCM messages a real IMU driver and a real
// wheel-odometry node would send (imu_t, odometry_t), plus the truth.
//
// Deterministic for a given seed and start time; next_due() never allocates,
// so the simulation can feed the real-time path in lockstep.
#include <cstdint>
#include <memory>

#include "core/time.hpp"
#include "runtime/config/config.hpp"

namespace rtfuse::sim {

struct SimMessage {
  const char* channel;
  const std::uint8_t* data;  // valid until the next call to next_due()
  int size;
  TimeNs stamp;
};

// Planar ground truth in the odom frame (the robot starts at the origin,
// facing +x). vx is the forward speed in base_link, vyaw the yaw rate.
struct TruthPose {
  double x, y, yaw, vx, vyaw;
};

// The wheel odometry's systematic error at one instant, before white noise.
struct LcmSimRobotSlip {
  double left, right;     // each wheel's fractional ground-speed error, |s| <= wheel_slip
  double speed_fraction;  // resulting forward-speed error: vx = v * (1 + speed_fraction)
  double yaw_rate_error;  // resulting yaw-rate error, rad/s (added to the true rate)
};

// The constant sensor biases this run drew from the seed (tests check the
// messages against them).
struct SimBiases {
  double gyro[3];   // rad/s, base_link x y z
  double accel[3];  // m/s^2
};

class SimLcmRobot {
 public:
  SimLcmRobot(const SimLcmConfig& cfg, TimeNs start);
  ~SimLcmRobot();
  SimLcmRobot(const SimLcmRobot&) = delete;
  SimLcmRobot& operator=(const SimLcmRobot&) = delete;

  // Stamp of the next message of any stream.
  TimeNs next_time() const noexcept;
  // The earliest pending message if its stamp is <= now (ties: imu, odom,
  // truth); false when none is due.
  bool next_due(TimeNs now, SimMessage* out) noexcept;

  TruthPose truth(TimeNs t) const noexcept;
  // Time to drive the figure eight once.
  double period_s() const noexcept;
  LcmSimRobotSlip slip(TimeNs t) const noexcept;
  const SimBiases& biases() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtfuse::sim
