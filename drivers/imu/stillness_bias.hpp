#pragma once
// Gyro bias from standstill (zero-velocity) periods: while the robot does not
// rotate, the gyro reads its bias alone, on every axis, including the one
// along gravity that no accelerometer observes (yaw).
//
// Stillness: over `window` seconds every sample must be quiet:
//  - |gyro - bias| (the rate after the current bias, norm) <= max_rate;
//  - each gyro axis within gyro_deviation of the run's running mean, and
//    the means of consecutive half-window blocks within block_change of each
//    other (a rate ramping by more than block_change / (window/2), 0.02
//    rad/s^2 by default: a turn starting or ending slowly);
//  - ||accel| - g| <= gravity_tolerance and each accel axis within
//    accel_deviation of its running mean (no start, stop or bump).
// One sample failing restarts the run. Per-sample thresholds against white
// noise of std s: gyro_deviation = 0.025 rad/s is 5 s for s = 0.005 rad/s
// (a noisy part at 200 Hz; an MPU-6050 at DLPF 3 has 0.0006), i.e. one false
// restart per ~2e6 axis-samples; accel_deviation = 0.2 m/s^2 is 5 s for
// 0.04 m/s^2 (the 6050 at DLPF 3 has 0.026). block_change = 0.005 rad/s is
// 5 sigma of the difference of two 0.25 s means at 0.005 rad/s, 200 Hz.
//
// Learning: quiet samples are averaged in blocks of window/2; a block is
// learnt only after the next block has also been quiet, so the samples just
// before a detected motion (a turn starting below max_rate) never are. Each
// learnt block moves the bias toward its mean by duration / (w + duration),
// w = stillness seconds already in the estimate, capped at time_constant:
// an exact average at first, then a low-pass with that time constant. Once
// the estimate holds time_constant seconds ("established"), a block may move
// each axis by at most max_correction_rate * its duration.
//
// Residual risk (not solvable from the IMU alone): a turn slower than about
// max_rate at constant speed reads like a bias: the gyro is constant, |a| is
// g, and a centripetal v w is constant in the body. Faster turns are refused
// by max_rate, and a rate ramping faster than block_change allows by the
// block test. A slower one is learnt: before the estimate is established, at
// the average's pace; after, by at most max_correction_rate per second of
// turning (20 s at 0.02 rad/s moves it by <= 4e-3 rad/s). Driving straight
// at constant speed is quiet too, and rightly: the gyro then reads only its
// bias (plus vibration). A bias beyond max_rate (an uncalibrated part) is
// never learnt: calibrate (AttitudeConfig::initial_gyro_bias) or raise
// max_rate.
//
// Fixed-size state, no allocation, bounded work per sample.
#include <cstdint>

#include <Eigen/Core>

namespace rtfuse::drivers {

struct StillnessConfig {
  bool enabled = true;
  double window = 0.5;             // s of quiet samples before the robot counts as still
  double max_rate = 0.03;          // rad/s: |gyro - bias| above this is rotation
  double gyro_deviation = 0.025;   // rad/s per axis from the running mean (see above)
  double block_change = 0.005;     // rad/s per axis between consecutive half-window means
  double accel_deviation = 0.2;    // m/s^2 per axis from the running mean
  // ||a| - g|, m/s^2: wide enough for an uncalibrated MPU's offset (~50 mg);
  // what it catches is free fall and bumps, the deviation test the rest.
  double gravity_tolerance = 0.5;
  double gravity = 9.80665;        // AttitudeFilter replaces it with its own
  double time_constant = 2.0;      // s: low-pass of the bias; the first stillness averages up to this
  double max_correction_rate = 2e-4;  // rad/s per s once established (2x a fast warm-up drift)
  // How fast the true bias may move between standstills (temperature),
  // rad/s per s: the reported uncertainty grows by this since the last one.
  double bias_drift_rate = 2e-5;
  double max_dt = 0.1;             // s: a longer gap restarts the window; AttitudeFilter replaces it
};

// nullptr when the configuration is usable, else what is wrong and the fix.
// An estimator given a bad one stays disabled and reports it (config_error()).
const char* stillness_config_error(const StillnessConfig& config) noexcept;

enum class StillnessState : std::uint8_t {
  kMoving,    // this sample was not quiet (or was rejected)
  kSettling,  // quiet, but for less than the window
  kStill,
};

struct StillnessStats {
  std::int64_t samples = 0;         // accepted by update()
  std::int64_t still_periods = 0;   // runs that reached the window
  std::int64_t restarts = 0;        // quiet runs ended by a sample that was not
  std::int64_t blocks_learnt = 0;
  std::int64_t rejected = 0;        // non-finite input or dt <= 0: counted, nothing changes
};

class StillnessBiasEstimator {
 public:
  explicit StillnessBiasEstimator(const StillnessConfig& config = {}) noexcept;

  // gyro rad/s, accel m/s^2 (specific force), both raw in base_link; dt s
  // since the previous sample. *bias: the bias the caller removes, read for
  // the rate test and moved toward the gyro while still. Never allocates.
  StillnessState update(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt,
                        Eigen::Vector3d* bias) noexcept;
  // dt seconds without a usable sample (a gap, a saturated accelerometer):
  // the run restarts.
  void interrupt(double dt) noexcept;
  // Forgets the run and everything learnt.
  void reset() noexcept;

  bool enabled() const noexcept { return enabled_; }
  bool still() const noexcept { return still_; }
  bool learnt() const noexcept { return weight_ > 0.0; }
  bool established() const noexcept { return weight_ >= config_.time_constant; }
  double learnt_seconds() const noexcept { return weight_; }
  double since_learnt() const noexcept { return since_learnt_; }
  // Std (rad/s, per axis) of what was learnt: white noise of density
  // noise_density (rad/s/sqrt(Hz)) averaged over the learnt seconds, plus
  // bias_drift_rate since then; never above unlearnt_sigma, which is also
  // the answer before anything was learnt.
  double residual_sigma(double noise_density, double unlearnt_sigma) const noexcept;
  const StillnessStats& stats() const noexcept { return stats_; }
  const StillnessConfig& config() const noexcept { return config_; }
  const char* config_error() const noexcept { return config_error_; }

 private:
  void end_run() noexcept;
  void learn(const Eigen::Vector3d& mean, double duration, Eigen::Vector3d* bias) noexcept;

  StillnessConfig config_;
  const char* config_error_;
  bool enabled_;
  // The current quiet run.
  double run_time_ = 0.0;
  std::int64_t run_samples_ = 0;
  Eigen::Vector3d gyro_mean_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mean_ = Eigen::Vector3d::Zero();
  bool still_ = false;
  // Block being filled, and the completed one waiting for the next to confirm it.
  Eigen::Vector3d block_sum_ = Eigen::Vector3d::Zero();  // gyro * dt
  double block_time_ = 0.0;
  Eigen::Vector3d held_mean_ = Eigen::Vector3d::Zero();
  double held_time_ = 0.0;
  bool held_ = false;
  // What was learnt.
  double weight_ = 0.0;        // s of stillness in the estimate, capped at time_constant
  double since_learnt_ = 0.0;  // s
  StillnessStats stats_;
};

}  // namespace rtfuse::drivers
