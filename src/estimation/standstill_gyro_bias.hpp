#pragma once
// A gyro's residual bias learnt while the wheels stand still.
//
// The IMU's own learner (drivers/imu/stillness_bias.hpp) decides stillness
// from the IMU alone, and a turn of a few mrad/s on a base smooth enough to
// pass its accelerometer test reads to it like a bias. The wheels tell the
// two apart: a standing base turns at exactly zero, whatever the gyro says.
// This learner averages the gyro's rates only over the wheels'
// standstills and takes the result off every rate after.
//
// Stillness is the wheels' word, by stamp. A still wheel sample (speed and
// yaw rate within the thresholds) opens a run; every later still one
// confirms the base still up to its stamp. Gyro samples stamped inside an
// open run fill a block; a full block (block_s long) is learnt once a wheel
// sample stamped at or after its last sample has confirmed it, so a block
// whose end might hold the start of a drive waits for the wheels' next
// word. A moving wheel sample ends the run and drops the block it was
// filling. Only stamps decide what counts as still, so whichever stream
// the loop sees first, nothing the wheels have not confirmed is learnt;
// the order decides only which samples fill a block (those taken while a
// full block waits are skipped), and a recording fixes that order.
//
// Learning: each learnt block of d seconds moves the bias toward its mean
// by d / (w + d), w the seconds already learnt, capped at time_constant_s:
// an exact average at first, then a low-pass with that time constant
// (a warming part's bias moves; a standstill of minutes should not weigh
// more than the last few).
//
// It trusts the wheels: a wheel sensor that reads zero while the base
// turns (both counters stuck, a lifted robot spun by hand) teaches that
// turn. A wheel sensor that falls silent teaches nothing: a full block
// waits for a confirmation that never comes.
//
// Bad input is counted and changes nothing: non-finite rates, speeds or
// stamps, and wheel samples older than the last one. Fixed-size, no
// allocation, bounded work per sample; double arithmetic one operation at
// a time (the build does not contract), so a replay learns the same bits.
#include <cstdint>

#include <Eigen/Core>

#include "core/time.hpp"

namespace rtfuse::est {

struct StandstillBiasParams {
  double block_s = 0.5;            // s of still gyro samples learnt at once
  double time_constant_s = 10.0;   // s: the low-pass's, once that much is learnt
  double still_speed_mps = 1e-3;   // |linear velocity| at or below: standing
  double still_yaw_rate = 1e-3;    // |yaw rate|, rad/s, at or below: not turning
};

// Empty when usable, else what is wrong (for the config loader).
const char* validate(const StandstillBiasParams& p) noexcept;

struct StandstillBiasStats {
  std::int64_t blocks = 0;       // learnt
  std::int64_t dropped = 0;      // blocks a moving wheel sample ended before confirmation
  std::int64_t rejected = 0;     // non-finite or out-of-order input
};

class StandstillGyroBias {
 public:
  explicit StandstillGyroBias(const StandstillBiasParams& params = {}) noexcept;

  // A wheel odometry sample: the base's linear speed (m/s, norm) and yaw
  // rate (rad/s) at `stamp`.
  void wheels(TimeNs stamp, double speed, double yaw_rate) noexcept;
  // A gyro sample (rad/s, the IMU's frame): learnt from when the wheels say
  // so; returns it with the bias learnt so far taken off.
  Eigen::Vector3d correct(TimeNs stamp, const Eigen::Vector3d& rate) noexcept;

  const Eigen::Vector3d& bias() const noexcept { return bias_; }
  double learnt_s() const noexcept { return weight_; }
  const StandstillBiasStats& stats() const noexcept { return stats_; }
  const StandstillBiasParams& params() const noexcept { return params_; }

 private:
  void drop_block() noexcept;
  void try_learn() noexcept;

  StandstillBiasParams params_;
  TimeNs block_ns_;
  bool any_wheels_ = false;
  TimeNs last_wheels_ = 0;
  bool in_run_ = false;
  TimeNs still_since_ = 0;      // the open run's first still wheel sample
  bool confirmed_ = false;
  TimeNs confirmed_until_ = 0;  // still up to here, in the open run
  // The block being filled.
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  std::int64_t count_ = 0;
  TimeNs first_ = 0;
  TimeNs last_ = 0;
  bool full_ = false;
  // What was learnt.
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  double weight_ = 0.0;  // s, capped at time_constant_s
  StandstillBiasStats stats_;
};

}  // namespace rtfuse::est
