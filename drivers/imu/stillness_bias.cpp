#include "drivers/imu/stillness_bias.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::drivers {

namespace {

bool finite(const Eigen::Vector3d& v) noexcept {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

bool positive(double v) noexcept { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) noexcept { return std::isfinite(v) && v >= 0.0; }

// Durations are sums of dt: a window of 100 x 0.005 s must count as 0.5 s.
constexpr double kTimeSlack = 1e-9;

}  // namespace

const char* stillness_config_error(const StillnessConfig& c) noexcept {
  if (!c.enabled) return nullptr;
  if (!positive(c.window)) return "stillness.window must be > 0 s (e.g. 0.5)";
  if (!positive(c.max_rate)) return "stillness.max_rate must be > 0 rad/s (e.g. 0.03)";
  if (!positive(c.gyro_deviation)) return "stillness.gyro_deviation must be > 0 rad/s (e.g. 5x the gyro noise)";
  if (!positive(c.block_change)) return "stillness.block_change must be > 0 rad/s (e.g. 0.005)";
  if (!positive(c.accel_deviation)) return "stillness.accel_deviation must be > 0 m/s^2 (e.g. 5x the accel noise)";
  if (!positive(c.gravity_tolerance)) return "stillness.gravity_tolerance must be > 0 m/s^2 (e.g. 0.5)";
  if (!positive(c.gravity)) return "stillness.gravity must be > 0 m/s^2 (9.80665)";
  if (!positive(c.time_constant)) return "stillness.time_constant must be > 0 s (e.g. 2)";
  if (!non_negative(c.max_correction_rate))
    return "stillness.max_correction_rate must be >= 0 rad/s per s (e.g. 2e-4; 0 freezes an established bias)";
  if (!non_negative(c.bias_drift_rate)) return "stillness.bias_drift_rate must be >= 0 rad/s per s (e.g. 2e-5)";
  if (!positive(c.max_dt)) return "stillness.max_dt must be > 0 s (a few sample periods)";
  return nullptr;
}

StillnessBiasEstimator::StillnessBiasEstimator(const StillnessConfig& config) noexcept
    : config_(config),
      config_error_(stillness_config_error(config)),
      enabled_(config.enabled && config_error_ == nullptr) {}

void StillnessBiasEstimator::reset() noexcept {
  end_run();
  weight_ = 0.0;
  since_learnt_ = 0.0;
}

void StillnessBiasEstimator::end_run() noexcept {
  run_time_ = 0.0;
  run_samples_ = 0;
  still_ = false;
  block_sum_.setZero();
  block_time_ = 0.0;
  held_ = false;
}

void StillnessBiasEstimator::interrupt(double dt) noexcept {
  if (!enabled_) return;
  if (run_samples_ > 0) ++stats_.restarts;
  end_run();
  if (positive(dt)) since_learnt_ += dt;
}

double StillnessBiasEstimator::residual_sigma(double noise_density, double unlearnt_sigma) const noexcept {
  if (weight_ <= 0.0) return unlearnt_sigma;
  const double n = std::isfinite(noise_density) ? noise_density : 0.0;
  const double drift = config_.bias_drift_rate * since_learnt_;
  return std::min(std::sqrt(n * n / weight_ + drift * drift), unlearnt_sigma);
}

void StillnessBiasEstimator::learn(const Eigen::Vector3d& mean, double duration, Eigen::Vector3d* bias) noexcept {
  const bool was_established = established();
  const double w = std::min(weight_, config_.time_constant);
  Eigen::Vector3d step = (duration / (w + duration)) * (mean - *bias);
  if (was_established) {
    // The average is settled: what still moves it is either slow drift or
    // a slow turn that passed for stillness; the bound caps the latter.
    const double m = config_.max_correction_rate * duration;
    step = step.cwiseMax(-m).cwiseMin(m);
  }
  *bias += step;
  weight_ = std::min(weight_ + duration, config_.time_constant);
  since_learnt_ = 0.0;
  ++stats_.blocks_learnt;
}

StillnessState StillnessBiasEstimator::update(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt,
                                              Eigen::Vector3d* bias) noexcept {
  if (!enabled_) return StillnessState::kMoving;
  if (bias == nullptr || !finite(gyro) || !finite(accel) || !finite(*bias) || !positive(dt)) {
    ++stats_.rejected;
    return still_ ? StillnessState::kStill : StillnessState::kMoving;
  }
  ++stats_.samples;
  since_learnt_ += dt;
  if (dt > config_.max_dt) {
    interrupt(0.0);
    return StillnessState::kMoving;
  }

  const bool absolute_quiet = std::abs(accel.norm() - config_.gravity) <= config_.gravity_tolerance &&
                              (gyro - *bias).norm() <= config_.max_rate;
  const bool consistent = run_samples_ == 0 ||
                          ((gyro - gyro_mean_).cwiseAbs().maxCoeff() <= config_.gyro_deviation &&
                           (accel - accel_mean_).cwiseAbs().maxCoeff() <= config_.accel_deviation);
  if (!absolute_quiet || !consistent) {
    if (run_samples_ > 0) ++stats_.restarts;
    end_run();
    // A sample that is quiet on its own but breaks the run starts the next.
    if (!absolute_quiet) return StillnessState::kMoving;
  }

  ++run_samples_;
  run_time_ += dt;
  // A growing average, then an average over about the last window.
  const double k = std::min(1.0, std::max(1.0 / static_cast<double>(run_samples_), dt / config_.window));
  gyro_mean_ += k * (gyro - gyro_mean_);
  accel_mean_ += k * (accel - accel_mean_);

  block_sum_ += gyro * dt;
  block_time_ += dt;
  if (block_time_ >= 0.5 * config_.window - kTimeSlack) {
    const Eigen::Vector3d mean = block_sum_ / block_time_;
    const double duration = block_time_;
    block_sum_.setZero();
    block_time_ = 0.0;
    if (held_ && (mean - held_mean_).cwiseAbs().maxCoeff() > config_.block_change) {
      // The rate is ramping (a turn starting or ending slowly): too slow
      // for the per-sample tests, but not a bias.
      ++stats_.restarts;
      end_run();
      return StillnessState::kMoving;
    }
    if (held_ && run_time_ >= config_.window - kTimeSlack) {
      // The held block was followed by a whole quiet, steady block.
      learn(held_mean_, held_time_, bias);
    }
    held_mean_ = mean;
    held_time_ = duration;
    held_ = true;
  }
  if (!still_ && run_time_ >= config_.window - kTimeSlack) {
    still_ = true;
    ++stats_.still_periods;
  }
  return still_ ? StillnessState::kStill : StillnessState::kSettling;
}

}  // namespace rtfuse::drivers
