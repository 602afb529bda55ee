#include "drivers/wheel/wheel_odometry.hpp"

#include <cmath>

namespace rtfuse::drivers {

namespace {
constexpr double kTwoPi = 6.28318530717958647692;
}

std::unique_ptr<WheelOdometry> WheelOdometry::create(const WheelOdometryConfig& config, std::string* error) {
  if (!validate_config(config, error)) return nullptr;
  return std::unique_ptr<WheelOdometry>(new WheelOdometry(config));
}

WheelOdometry::WheelOdometry(const WheelOdometryConfig& config)
    : config_(config),
      meters_per_count_(kTwoPi * config.wheel_radius_m / (config.counts_per_rev * config.gear_ratio)),
      track_(config.track_width_m *
             (config.kinematics == DriveKinematics::kSkidSteer ? config.skid_track_factor : 1.0)) {}

bool WheelOdometry::update(const EncoderReading* readings, int n, WheelTwist* out) noexcept {
  ++stats_.updates;
  if (readings == nullptr || out == nullptr || n <= 0) {
    ++stats_.bad_input;
    return false;
  }
  TimeNs stamp = 0;
  bool any_valid = false;
  for (int w = 0; w < config_.wheel_count; ++w) {
    const int idx = config_.wheels[static_cast<std::size_t>(w)].encoder_index;
    if (idx >= n) {
      ++stats_.bad_input;  // fewer encoders than the wheel config names: a wiring error upstream
      return false;
    }
    const EncoderReading& r = readings[idx];
    if (r.valid && (!any_valid || r.stamp > stamp)) stamp = r.stamp;
    any_valid = any_valid || r.valid;
  }
  if (!any_valid) {
    ++stats_.no_side;
    for (WheelMemory& m : prev_) m.valid = false;
    return false;
  }
  if (has_prev_ && stamp <= prev_stamp_) {
    ++stats_.stale;
    return false;
  }

  const bool reseed = !has_prev_ || stamp - prev_stamp_ > config_.max_gap_ns;
  const TimeNs dt_ns = stamp - prev_stamp_;
  double sum[2] = {0.0, 0.0};
  int used[2] = {0, 0};
  for (int w = 0; w < config_.wheel_count; ++w) {
    const WheelConfig& wc = config_.wheels[static_cast<std::size_t>(w)];
    const EncoderReading& r = readings[wc.encoder_index];
    WheelMemory& m = prev_[static_cast<std::size_t>(w)];
    // A reading from another SYNC than the newest is not part of this set.
    const bool now_ok = r.valid && r.stamp == stamp;
    if (!reseed && now_ok && m.valid && m.segment == r.segment) {
      const int side = wc.side == WheelSide::kLeft ? 0 : 1;
      sum[side] += static_cast<double>(wc.sign) * static_cast<double>(r.counts - m.counts);
      ++used[side];
    }
    m.valid = now_ok;
    m.counts = r.counts;
    m.segment = r.segment;
  }
  has_prev_ = true;
  prev_stamp_ = stamp;
  if (reseed) {
    ++stats_.reseeds;
    return false;
  }
  if (used[0] == 0 || used[1] == 0) {
    ++stats_.no_side;
    return false;
  }

  const double dt = ns_to_sec(dt_ns);
  const double v_l = sum[0] / used[0] * meters_per_count_ / dt;
  const double v_r = sum[1] / used[1] * meters_per_count_ / dt;
  const double q = meters_per_count_ / dt;  // one count per sample period
  const double slip = config_.slip_fraction;
  const double var_l = (slip * v_l) * (slip * v_l) + q * q / used[0];
  const double var_r = (slip * v_r) * (slip * v_r) + q * q / used[1];
  const double b = track_;

  WheelTwist t;
  t.stamp = stamp;
  t.dt_ns = dt_ns;
  t.v_left = v_l;
  t.v_right = v_r;
  t.vx = 0.5 * (v_l + v_r);
  t.vyaw = (v_r - v_l) / b;
  t.var_vx = 0.25 * (var_l + var_r) + config_.vx_sigma_floor_mps * config_.vx_sigma_floor_mps;
  t.var_vyaw = (var_l + var_r) / (b * b) + config_.vyaw_sigma_floor_radps * config_.vyaw_sigma_floor_radps;
  if (config_.kinematics == DriveKinematics::kSkidSteer) {
    t.var_vyaw += config_.skid_yaw_variance_per_mps * std::fabs(v_r - v_l);
  }
  t.cov_vx_vyaw = (var_r - var_l) / (2.0 * b);
  t.wheels_used = used[0] + used[1];
  if (!std::isfinite(t.vx) || !std::isfinite(t.vyaw) || !std::isfinite(t.var_vx) || !std::isfinite(t.var_vyaw) ||
      !std::isfinite(t.cov_vx_vyaw)) {
    ++stats_.bad_input;  // counts so large the arithmetic overflowed
    return false;
  }
  pose_ = integrate_arc(pose_, t.vx * dt, t.vyaw * dt);
  pose_stamp_ = stamp;
  *out = t;
  ++stats_.outputs;
  return true;
}

}  // namespace rtfuse::drivers
