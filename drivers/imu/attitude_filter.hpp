#pragma once
// Attitude from a 6-axis IMU: Madgwick (gradient descent on the gravity
// direction) or Mahony (nonlinear complementary filter), both with a gyro-bias
// estimate, plus a covariance model of what they deliver.
//
// Frames: the orientation is base_link in a gravity-aligned frame (z up),
// q = world_R_base, so a level robot at rest has q = identity and measures
// accel = (0, 0, +g). Yaw starts at 0; nothing observes it, so it drifts with
// the gyro and its variance only grows. Likewise the gyro-bias component along
// gravity is not observable from an accelerometer: with a StillnessConfig
// (the two-argument constructor; MpuImu passes one) it is learnt, with the
// other axes, while the robot stands still (stillness_bias.hpp); without one
// it is not estimated.
//
// Covariance model (roll/pitch, each; all fixed-size, no allocation):
//  - both filters pull the tilt toward the accelerometer's with a per-sample
//    gain alpha: Mahony alpha = kp dt; Madgwick takes normalised steps of
//    s = 2 beta dt, whose small-signal gain against tilt noise sigma is
//    alpha = 0.627 s / sigma (E[1/|n|]/2 for 2-D Gaussian noise n).
//  - the tilt error P follows P <- (1 - alpha)^2 P + q with q = alpha^2
//    sigma^2 (Mahony) or s^2 / 2 (Madgwick's steps), plus the gyro's angle
//    random walk N^2 dt; sigma^2 = accel variance / g^2.
//  - |a| away from g means the robot accelerates: the accelerometer then
//    points off vertical by up to atan(a_h / g), a_h^2 = |a|^2 - g^2 being the
//    horizontal acceleration that would explain |a| (the worst case, as the
//    direction is unknown). |a|^2 - g^2 is averaged with the filter's gain
//    (the error builds up at that pace), ignored below a threshold (noise and
//    gravity_tolerance), and the resulting tilt bias decays no faster than
//    the filter corrects once |a| is back at g; its square is added to the
//    variance. An |a|-based detector cannot see a small horizontal
//    acceleration: below ~sqrt(2 g gravity_tolerance) it goes unreported.
// Yaw variance = N^2 T (angle random walk) + (integral of sigma_b dt)^2 (the
// bias error, fully correlated over time) + gaps, T the time since
// initialisation; sigma_b = yaw_bias_sigma until a standstill taught the bias,
// then what the stillness estimator says is left (its averaging noise plus
// drift since), never more than yaw_bias_sigma.
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "drivers/imu/stillness_bias.hpp"

namespace rtfuse::drivers {

enum class AttitudeAlgorithm : std::uint8_t { kMadgwick, kMahony };

struct AttitudeConfig {
  AttitudeAlgorithm algorithm = AttitudeAlgorithm::kMahony;
  double beta = 0.05;   // Madgwick gradient step, 1/s (tilt slews at up to 2 beta rad/s)
  double zeta = 0.005;  // Madgwick bias gain, rad/s^2 per unit of normalised error rate
  double kp = 1.0;      // Mahony proportional gain, rad/s per unit error (1/s crossover)
  double ki = 0.05;     // Mahony integral gain: the bias estimate integrates ki * error
  double max_bias = 0.35;  // rad/s; bias estimate clamp (the 6050's initial ZRO tolerance, 20 deg/s)
  Eigen::Vector3d initial_gyro_bias = Eigen::Vector3d::Zero();  // rad/s, e.g. from a calibration at rest

  double max_dt = 0.1;  // s; a longer gap re-initialises roll/pitch from the accelerometer
  double gravity = 9.80665;
  // Below this |a| (m/s^2) the accelerometer carries no direction (free fall,
  // a zeroed sample): the sample only propagates with the gyro.
  double min_accel = 0.5;
  // ||a| - g| that is the accelerometer's own error (scale, offset), not
  // acceleration, m/s^2. Calibrated chips: a few hundredths; an uncalibrated
  // MPU can be 0.3 off, which also hides horizontal accelerations below
  // sqrt(2 g tolerance) from the covariance.
  double gravity_tolerance = 0.05;

  // Noise, per axis. MpuImu overwrites these from its measurement-noise model.
  double accel_variance = 6.8e-4;        // (m/s^2)^2 per sample (6050, DLPF 44 Hz)
  double gyro_noise_density = 8.73e-5;   // rad/s/sqrt(Hz): angle random walk (6050: 0.005 deg/s/sqrt(Hz))
  double yaw_bias_sigma = 0.0873;        // rad/s: unestimated bias about gravity (6500/9250 ZRO tolerance, 5 deg/s)
  double gap_yaw_rate_sigma = 1.0;       // rad/s: how fast the robot may turn unseen during a gap
};

enum class AttitudeUpdate : std::uint8_t {
  kUpdated,
  kInitialised,         // roll/pitch taken from this sample's accelerometer
  kGapReinitialised,    // dt > max_dt: roll/pitch from the accelerometer, yaw and bias kept
  kWaitingForGravity,   // not initialised and this accel carries no direction
  kRejectedNonFinite,   // counted; the state is untouched
  kRejectedDt,          // dt <= 0 (stamps not increasing); counted, untouched
};

struct AttitudeStats {
  std::int64_t updates = 0;
  std::int64_t initialisations = 0;
  std::int64_t gap_reinits = 0;
  std::int64_t rejected_non_finite = 0;
  std::int64_t rejected_dt = 0;
  std::int64_t accel_skipped = 0;  // samples propagated by the gyro alone
};

class AttitudeFilter {
 public:
  // Without bias learning at standstill.
  explicit AttitudeFilter(const AttitudeConfig& config = {}) noexcept;
  // With it (when stillness.enabled); its gravity and max_dt are replaced by
  // this config's.
  AttitudeFilter(const AttitudeConfig& config, const StillnessConfig& stillness) noexcept;

  // gyro: rad/s as measured (bias not removed); accel: m/s^2 specific force
  // (gravity included), both in base_link; dt: s since the previous sample.
  // accel_usable = false propagates with the gyro only (a saturated
  // accelerometer). Never allocates.
  AttitudeUpdate update(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt,
                        bool accel_usable = true) noexcept;

  // Back to uninitialised (bias back to initial_gyro_bias, standstill learning forgotten).
  void reset() noexcept;
  // Initialised at a known orientation, with the single-sample tilt variance.
  void reset(const Eigen::Quaterniond& world_R_base) noexcept;
  // Extra uncertainty from outside the model (a saturated gyro).
  void inflate(double roll_pitch_variance, double yaw_variance) noexcept;
  void set_noise(double accel_variance, double gyro_noise_density) noexcept;

  bool initialised() const noexcept { return initialised_; }
  const Eigen::Quaterniond& orientation() const noexcept { return q_; }
  const Eigen::Vector3d& gyro_bias() const noexcept { return bias_; }
  // The last gyro sample minus the bias estimate (no attitude correction in it).
  const Eigen::Vector3d& angular_velocity() const noexcept { return omega_; }
  double roll_pitch_variance() const noexcept { return tilt_var_ + disturbance_ * disturbance_; }
  double yaw_variance() const noexcept;
  // Variance of the yaw-rate bias error, (rad/s)^2: yaw_bias_sigma^2 until a
  // standstill taught the bias, then the stillness estimator's residual.
  double yaw_rate_bias_variance() const noexcept;
  const StillnessBiasEstimator& stillness() const noexcept { return still_; }
  // Over roll, pitch, yaw (sensor_msgs/Imu's orientation_covariance).
  Eigen::Matrix3d orientation_covariance() const noexcept;
  const AttitudeStats& stats() const noexcept { return stats_; }
  const AttitudeConfig& config() const noexcept { return config_; }

 private:
  struct Gain {
    double alpha;     // small-signal pull toward the accelerometer's tilt per sample
    double max_step;  // the most the tilt can move toward it in one sample, rad
    double injected;  // tilt variance added per sample by the correction itself
  };

  bool accel_has_direction(const Eigen::Vector3d& accel) const noexcept;
  void init_tilt(const Eigen::Vector3d& accel, double yaw) noexcept;
  void step_madgwick(const Eigen::Vector3d& gyro, const Eigen::Vector3d* accel_dir, double dt) noexcept;
  void step_mahony(const Eigen::Vector3d& gyro, const Eigen::Vector3d* accel_dir, double dt) noexcept;
  void clamp_bias() noexcept;
  Gain gain(double dt) const noexcept;
  // Tilt error (rad) from an averaged |a|^2 - g^2 (m^2/s^4).
  double disturbance_from(double excess_sq, double alpha) const noexcept;
  void propagate_variance(double dt, const Eigen::Vector3d* accel, double accel_norm) noexcept;
  double bias_sigma() const noexcept;
  double tilt_sigma2() const noexcept;

  AttitudeConfig config_;
  bool initialised_ = false;
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_ = Eigen::Vector3d::Zero();
  double tilt_var_ = 0.0;
  double accel_excess_ = 0.0;  // |a|^2 - g^2 averaged with the filter's gain
  double disturbance_ = 0.0;   // rad, tilt bias carried from accelerations
  double yaw_base_var_ = 0.0;
  double yaw_arw_var_ = 0.0;
  double yaw_bias_angle_ = 0.0;  // rad: integral of the yaw-rate bias sigma since initialisation
  StillnessBiasEstimator still_;
  AttitudeStats stats_;
};

}  // namespace rtfuse::drivers
