#include "drivers/imu/attitude_filter.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::drivers {

namespace {

// Small-signal gain of a normalised (sign-like) correction step against
// 2-D Gaussian noise: E[1/|n|] / 2 = sqrt(pi/2) / (2 sigma).
constexpr double kNormalisedStepGain = 0.6267;
// Reported variances never reach exactly zero: a consumer inverting them
// (an EKF's innovation covariance) must not divide by zero.
constexpr double kVarianceFloor = 1e-9;

bool finite(const Eigen::Vector3d& v) noexcept {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

// Body-frame rotation over one step, exact for a constant rate.
Eigen::Quaterniond delta_rotation(const Eigen::Vector3d& rate, double dt) noexcept {
  const Eigen::Vector3d theta = rate * dt;
  const double angle = theta.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, theta / angle));
}

// Gravity direction (up) in base_link for q = world_R_base: the third row of R.
Eigen::Vector3d up_in_body(const Eigen::Quaterniond& q) noexcept {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  return {2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z};
}

double yaw_of(const Eigen::Quaterniond& q) noexcept {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

StillnessConfig no_stillness() noexcept {
  StillnessConfig s;
  s.enabled = false;
  return s;
}

// The estimator judges |a| against the same gravity and sees no gap the
// filter would not already call one.
StillnessConfig stillness_for(const AttitudeConfig& c, StillnessConfig s) noexcept {
  s.gravity = c.gravity;
  s.max_dt = c.max_dt;
  return s;
}

}  // namespace

AttitudeFilter::AttitudeFilter(const AttitudeConfig& config) noexcept : AttitudeFilter(config, no_stillness()) {}

AttitudeFilter::AttitudeFilter(const AttitudeConfig& config, const StillnessConfig& stillness) noexcept
    : config_(config), still_(stillness_for(config, stillness)) {
  reset();
}

void AttitudeFilter::reset() noexcept {
  initialised_ = false;
  q_ = Eigen::Quaterniond::Identity();
  bias_ = finite(config_.initial_gyro_bias) ? config_.initial_gyro_bias : Eigen::Vector3d::Zero();
  clamp_bias();
  omega_.setZero();
  tilt_var_ = 0.0;
  accel_excess_ = 0.0;
  disturbance_ = 0.0;
  yaw_base_var_ = 0.0;
  yaw_arw_var_ = 0.0;
  yaw_bias_angle_ = 0.0;
  still_.reset();
}

void AttitudeFilter::reset(const Eigen::Quaterniond& world_R_base) noexcept {
  reset();
  const double n = world_R_base.norm();
  q_ = (std::isfinite(n) && n > 1e-6) ? world_R_base.normalized() : Eigen::Quaterniond::Identity();
  tilt_var_ = tilt_sigma2();
  initialised_ = true;
}

void AttitudeFilter::inflate(double roll_pitch_variance, double yaw_variance) noexcept {
  if (std::isfinite(roll_pitch_variance) && roll_pitch_variance > 0) tilt_var_ += roll_pitch_variance;
  if (std::isfinite(yaw_variance) && yaw_variance > 0) yaw_base_var_ += yaw_variance;
}

void AttitudeFilter::set_noise(double accel_variance, double gyro_noise_density) noexcept {
  if (std::isfinite(accel_variance) && accel_variance > 0) config_.accel_variance = accel_variance;
  if (std::isfinite(gyro_noise_density) && gyro_noise_density > 0) config_.gyro_noise_density = gyro_noise_density;
}

double AttitudeFilter::tilt_sigma2() const noexcept {
  const double g = config_.gravity > 0 ? config_.gravity : 9.80665;
  return std::max(config_.accel_variance, 0.0) / (g * g);
}

double AttitudeFilter::bias_sigma() const noexcept {
  return still_.residual_sigma(config_.gyro_noise_density, std::max(config_.yaw_bias_sigma, 0.0));
}

double AttitudeFilter::yaw_rate_bias_variance() const noexcept {
  const double s = bias_sigma();
  return s * s;
}

double AttitudeFilter::yaw_variance() const noexcept {
  return yaw_base_var_ + yaw_arw_var_ + yaw_bias_angle_ * yaw_bias_angle_;
}

Eigen::Matrix3d AttitudeFilter::orientation_covariance() const noexcept {
  const double rp = std::max(roll_pitch_variance(), kVarianceFloor);
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c(0, 0) = rp;
  c(1, 1) = rp;
  c(2, 2) = std::max(yaw_variance(), kVarianceFloor);
  return c;
}

bool AttitudeFilter::accel_has_direction(const Eigen::Vector3d& accel) const noexcept {
  return accel.norm() >= config_.min_accel;
}

void AttitudeFilter::clamp_bias() noexcept {
  const double m = std::max(config_.max_bias, 0.0);
  for (int i = 0; i < 3; ++i) bias_[i] = std::clamp(bias_[i], -m, m);
}

void AttitudeFilter::init_tilt(const Eigen::Vector3d& accel, double yaw) noexcept {
  const double roll = std::atan2(accel.y(), accel.z());
  // Not std::hypot: glibc's hypot rounds differently on x86-64 and aarch64,
  // and a recording made on the robot must replay bit-exactly on a laptop.
  const double pitch = std::atan2(-accel.x(), std::sqrt(accel.y() * accel.y() + accel.z() * accel.z()));
  q_ = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  q_.normalize();
  tilt_var_ = tilt_sigma2();
  const double g = config_.gravity;
  accel_excess_ = accel.squaredNorm() - g * g;
  disturbance_ = disturbance_from(accel_excess_, 1.0);
}

double AttitudeFilter::disturbance_from(double excess_sq, double alpha) const noexcept {
  const double g = config_.gravity;
  // |a|^2 - g^2 is the squared horizontal acceleration if all of the extra
  // acceleration is horizontal: the worst case, since its direction is
  // unknown. Below the threshold it is noise (per-sample std 2 g sigma_a,
  // averaged by the gain) or the accelerometer's own scale error.
  const double sigma_a = std::sqrt(std::max(config_.accel_variance, 0.0));
  const double averaged = alpha >= 1.0 ? 1.0 : std::sqrt(alpha / (2.0 - alpha));
  const double threshold = 2.0 * g * config_.gravity_tolerance + 3.0 * 2.0 * g * sigma_a * averaged;
  const double m = std::abs(excess_sq);
  return m > threshold ? std::atan2(std::sqrt(m), g) : 0.0;
}

AttitudeFilter::Gain AttitudeFilter::gain(double dt) const noexcept {
  const double sigma2 = tilt_sigma2();
  if (config_.algorithm == AttitudeAlgorithm::kMahony) {
    const double a = std::clamp(config_.kp * dt, 0.0, 1.0);
    return Gain{a, std::max(config_.kp * dt, 0.0), a * a * sigma2};
  }
  const double s = std::max(2.0 * config_.beta * dt, 0.0);
  const double sigma = std::max(std::sqrt(sigma2), 1e-12);
  const double a = std::min(1.0, kNormalisedStepGain * s / sigma);
  return Gain{a, s, 0.5 * s * s};
}

void AttitudeFilter::propagate_variance(double dt, const Eigen::Vector3d* accel, double accel_norm) noexcept {
  const double arw = config_.gyro_noise_density * config_.gyro_noise_density * dt;
  if (accel != nullptr) {
    const Gain k = gain(dt);
    tilt_var_ = (1.0 - k.alpha) * (1.0 - k.alpha) * tilt_var_ + k.injected + arw;
    const double g = config_.gravity;
    accel_excess_ += k.alpha * (accel_norm * accel_norm - g * g - accel_excess_);
    // The error an acceleration left behind decays no faster than the filter
    // corrects: by alpha of it per sample, and at most max_step (Madgwick's
    // fixed-size steps).
    const double decayed = disturbance_ - std::min(k.alpha * disturbance_, k.max_step);
    disturbance_ = std::max(disturbance_from(accel_excess_, k.alpha), decayed);
  } else {
    tilt_var_ += arw;
  }
  yaw_arw_var_ += arw;
  yaw_bias_angle_ += bias_sigma() * dt;
}

void AttitudeFilter::step_madgwick(const Eigen::Vector3d& gyro, const Eigen::Vector3d* accel_dir, double dt) noexcept {
  Eigen::Vector3d correction = Eigen::Vector3d::Zero();
  if (accel_dir != nullptr) {
    // Objective f = up_in_body(q) - a_hat; gradient J^T f over (w, x, y, z).
    const double w = q_.w(), x = q_.x(), y = q_.y(), z = q_.z();
    const Eigen::Vector3d f = up_in_body(q_) - *accel_dir;
    const Eigen::Vector4d grad(-2 * y * f.x() + 2 * x * f.y() + 2 * w * f.z(),  //
                               2 * z * f.x() + 2 * w * f.y() - 2 * x * f.z(),   //
                               -2 * w * f.x() + 2 * z * f.y() - 2 * y * f.z(),  //
                               2 * x * f.x() + 2 * y * f.y() + 2 * z * f.z());
    const double n = grad.norm();
    if (n > 1e-12) {
      const Eigen::Quaterniond step(grad[0] / n, grad[1] / n, grad[2] / n, grad[3] / n);
      // The step as a body rate: qdot = q (0, w) / 2  =>  w = 2 q* qdot.
      const Eigen::Vector3d error_rate = 2.0 * (q_.conjugate() * step).vec();
      bias_ += config_.zeta * error_rate * dt;
      clamp_bias();
      correction = -config_.beta * error_rate;
    }
  }
  q_ = (q_ * delta_rotation(gyro - bias_ + correction, dt)).normalized();
}

void AttitudeFilter::step_mahony(const Eigen::Vector3d& gyro, const Eigen::Vector3d* accel_dir, double dt) noexcept {
  Eigen::Vector3d correction = Eigen::Vector3d::Zero();
  if (accel_dir != nullptr) {
    // Rotating the estimate about a_hat x v turns v toward a_hat.
    const Eigen::Vector3d e = accel_dir->cross(up_in_body(q_));
    bias_ -= config_.ki * e * dt;
    clamp_bias();
    correction = config_.kp * e;
  }
  q_ = (q_ * delta_rotation(gyro - bias_ + correction, dt)).normalized();
}

AttitudeUpdate AttitudeFilter::update(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt,
                                      bool accel_usable) noexcept {
  if (!finite(gyro) || !std::isfinite(dt) || (accel_usable && !finite(accel))) {
    ++stats_.rejected_non_finite;
    return AttitudeUpdate::kRejectedNonFinite;
  }
  const bool has_direction = accel_usable && accel_has_direction(accel);
  if (!initialised_) {
    omega_ = gyro - bias_;
    if (!has_direction) return AttitudeUpdate::kWaitingForGravity;
    init_tilt(accel, 0.0);
    initialised_ = true;
    ++stats_.initialisations;
    return AttitudeUpdate::kInitialised;
  }
  if (dt <= 0.0) {
    ++stats_.rejected_dt;
    return AttitudeUpdate::kRejectedDt;
  }
  omega_ = gyro - bias_;
  if (dt > config_.max_dt) {
    // Rotation during the gap was not seen: yaw keeps its value (consumers
    // integrating it differentially see no jump) but its variance grows.
    const double unseen = dt * config_.gap_yaw_rate_sigma;
    yaw_base_var_ += unseen * unseen;
    yaw_arw_var_ += config_.gyro_noise_density * config_.gyro_noise_density * dt;
    yaw_bias_angle_ += bias_sigma() * dt;
    still_.interrupt(dt);
    if (has_direction) {
      init_tilt(accel, yaw_of(q_));
    } else {
      tilt_var_ += unseen * unseen;
    }
    ++stats_.gap_reinits;
    return AttitudeUpdate::kGapReinitialised;
  }

  Eigen::Vector3d dir = Eigen::Vector3d::Zero();
  const double norm = accel.norm();
  const Eigen::Vector3d* dir_ptr = nullptr;
  if (has_direction) {
    dir = accel / norm;
    dir_ptr = &dir;
  } else {
    ++stats_.accel_skipped;
  }
  // At standstill the raw gyro is the bias, on every axis: learnt before the
  // step so this sample's yaw already integrates without it.
  if (has_direction) {
    (void)still_.update(gyro, accel, dt, &bias_);
    clamp_bias();
  } else {
    still_.interrupt(dt);
  }
  if (config_.algorithm == AttitudeAlgorithm::kMadgwick) {
    step_madgwick(gyro, dir_ptr, dt);
  } else {
    step_mahony(gyro, dir_ptr, dt);
  }
  omega_ = gyro - bias_;
  propagate_variance(dt, dir_ptr, norm);
  ++stats_.updates;
  return AttitudeUpdate::kUpdated;
}

}  // namespace rtfuse::drivers
