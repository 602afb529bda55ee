#include "drivers/wheel/wheel_odometry_config.hpp"

#include <cmath>
#include <cstdio>

#include "drivers/config_error.hpp"

namespace rtfuse::drivers {

namespace {

constexpr const char* kWho = "wheel odometry";

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

bool validate_config(const WheelOdometryConfig& c, std::string* error) {
  if (!positive(c.track_width_m)) {
    return config_fail(error, kWho, "track_width_m = %g: must be > 0 (distance between the left and right wheels)",
                c.track_width_m);
  }
  if (!positive(c.wheel_radius_m)) return config_fail(error, kWho, "wheel_radius_m = %g: must be > 0", c.wheel_radius_m);
  if (!positive(c.counts_per_rev)) {
    return config_fail(error, kWho, "counts_per_rev = %g: must be > 0 (encoder counts per encoder-shaft revolution)",
                c.counts_per_rev);
  }
  if (!positive(c.gear_ratio)) {
    return config_fail(error, kWho, "gear_ratio = %g: must be > 0 (encoder revolutions per wheel revolution; 1 on the wheel axle)",
                c.gear_ratio);
  }
  if (c.wheel_count < 2 || c.wheel_count > kMaxWheels) {
    return config_fail(error, kWho, "wheel_count = %d: configure 2..%d wheels (at least one per side)", c.wheel_count, kMaxWheels);
  }
  int left = 0;
  int right = 0;
  for (int i = 0; i < c.wheel_count; ++i) {
    const WheelConfig& w = c.wheels[static_cast<std::size_t>(i)];
    if (w.encoder_index < 0 || w.encoder_index >= kMaxEncoderNodes) {
      return config_fail(error, kWho, "wheels[%d].encoder_index = %d: must be 0..%d (the encoder node's position in the CANopen "
                  "node list)", i, w.encoder_index, kMaxEncoderNodes - 1);
    }
    if (w.sign != 1 && w.sign != -1) {
      return config_fail(error, kWho, "wheels[%d].sign = %d: must be +1 or -1 (-1 for a mirrored motor)", i, w.sign);
    }
    for (int j = 0; j < i; ++j) {
      if (c.wheels[static_cast<std::size_t>(j)].encoder_index == w.encoder_index) {
        return config_fail(error, kWho, "wheels[%d] and wheels[%d] both use encoder_index %d: each wheel needs its own encoder", j,
                    i, w.encoder_index);
      }
    }
    (w.side == WheelSide::kLeft ? left : right) += 1;
  }
  if (left == 0 || right == 0) {
    return config_fail(error, kWho, "no %s wheel: odometry needs at least one wheel on each side", left == 0 ? "left" : "right");
  }
  if (!std::isfinite(c.skid_track_factor) || c.skid_track_factor < 1.0) {
    return config_fail(error, kWho, "skid_track_factor = %g: must be >= 1 (effective track / geometric track)",
                c.skid_track_factor);
  }
  if (c.kinematics == DriveKinematics::kDifferential && c.skid_track_factor != 1.0) {
    return config_fail(error, kWho, "skid_track_factor = %g with differential kinematics: it applies only to skid_steer; set "
                "kinematics = skid_steer or leave the factor at 1", c.skid_track_factor);
  }
  if (!non_negative(c.vx_sigma_floor_mps) || !non_negative(c.vyaw_sigma_floor_radps) ||
      !non_negative(c.slip_fraction) || !non_negative(c.skid_yaw_variance_per_mps)) {
    return config_fail(error, kWho, "noise model: vx_sigma_floor_mps %g, vyaw_sigma_floor_radps %g, slip_fraction %g, "
                "skid_yaw_variance_per_mps %g must all be finite and >= 0", c.vx_sigma_floor_mps,
                c.vyaw_sigma_floor_radps, c.slip_fraction, c.skid_yaw_variance_per_mps);
  }
  if (c.max_gap_ns <= 0) {
    return config_fail(error, kWho, "max_gap_ns = %lld: must be > 0 (a few SYNC periods)", static_cast<long long>(c.max_gap_ns));
  }
  return true;
}

}  // namespace rtfuse::drivers
