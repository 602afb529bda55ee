#include "estimation/standstill_gyro_bias.hpp"

#include <cmath>

namespace rtfuse::est {

const char* validate(const StandstillBiasParams& p) noexcept {
  if (!(p.block_s >= 0.05 && p.block_s <= 60.0)) return "block must be in [0.05, 60] s";
  if (!(p.time_constant_s >= p.block_s && p.time_constant_s <= 86400.0)) {
    return "time_constant must be at least the block and at most a day (s)";
  }
  if (!(p.still_speed_mps >= 0.0 && p.still_speed_mps <= 0.1)) return "still_speed must be in [0, 0.1] m/s";
  if (!(p.still_yaw_rate >= 0.0 && p.still_yaw_rate <= 0.1)) return "still_yaw_rate must be in [0, 0.1] rad/s";
  return "";
}

StandstillGyroBias::StandstillGyroBias(const StandstillBiasParams& params) noexcept
    : params_(params), block_ns_(static_cast<TimeNs>(std::llround(params.block_s * 1e9))) {}

void StandstillGyroBias::drop_block() noexcept {
  if (count_ > 0) ++stats_.dropped;
  sum_.setZero();
  count_ = 0;
  full_ = false;
}

void StandstillGyroBias::wheels(TimeNs stamp, double speed, double yaw_rate) noexcept {
  if (!std::isfinite(speed) || !std::isfinite(yaw_rate) || (any_wheels_ && stamp < last_wheels_)) {
    ++stats_.rejected;
    return;
  }
  any_wheels_ = true;
  last_wheels_ = stamp;
  const bool still = std::fabs(speed) <= params_.still_speed_mps && std::fabs(yaw_rate) <= params_.still_yaw_rate;
  if (!still) {
    in_run_ = false;
    confirmed_ = false;
    drop_block();
    return;
  }
  if (!in_run_) {
    in_run_ = true;
    still_since_ = stamp;
    return;
  }
  confirmed_ = true;
  confirmed_until_ = stamp;
  try_learn();
}

Eigen::Vector3d StandstillGyroBias::correct(TimeNs stamp, const Eigen::Vector3d& rate) noexcept {
  if (!rate.allFinite()) {
    ++stats_.rejected;
    return rate;  // the filter refuses it; nothing here changes
  }
  if (in_run_ && !full_ && stamp >= still_since_ && (count_ == 0 || stamp >= last_)) {
    if (count_ == 0) first_ = stamp;
    last_ = stamp;
    sum_ += rate;
    ++count_;
    full_ = last_ - first_ >= block_ns_;
    try_learn();
  }
  return rate - bias_;
}

void StandstillGyroBias::try_learn() noexcept {
  if (!full_ || !confirmed_ || confirmed_until_ < last_) return;
  const double d = static_cast<double>(last_ - first_) * 1e-9;
  const Eigen::Vector3d mean = sum_ / static_cast<double>(count_);
  const double w = weight_ < params_.time_constant_s ? weight_ : params_.time_constant_s;
  bias_ += (mean - bias_) * (d / (w + d));
  weight_ = w + d < params_.time_constant_s ? w + d : params_.time_constant_s;
  ++stats_.blocks;
  sum_.setZero();
  count_ = 0;
  full_ = false;
}

}  // namespace rtfuse::est
