#pragma once
// Geometry and noise model of a wheeled base whose wheels carry the CANopen
// encoders: plain values, filled by the runtime's TOML loader.
#include <array>
#include <cstdint>
#include <string>

#include "core/time.hpp"
#include "drivers/canopen/encoder_reading.hpp"
#include "drivers/wheel/drive_kinematics.hpp"

namespace rtfuse::drivers {

constexpr int kMaxWheels = kMaxEncoderNodes;

enum class WheelSide : std::uint8_t { kLeft, kRight };

struct WheelConfig {
  int encoder_index = 0;  // into the encoder readings (CanopenEncoders node order)
  WheelSide side = WheelSide::kLeft;
  int sign = 1;  // -1 for a mirrored motor whose counts fall when the wheel rolls forward
};

struct WheelOdometryConfig {
  DriveKinematics kinematics = DriveKinematics::kDifferential;
  double track_width_m = 0.0;   // between left and right wheel contact lines
  double wheel_radius_m = 0.0;
  double counts_per_rev = 0.0;  // encoder counts per encoder-shaft revolution
  double gear_ratio = 1.0;      // encoder revolutions per wheel revolution
  int wheel_count = 0;
  std::array<WheelConfig, kMaxWheels> wheels{};

  // Skid steer, ICR model: yaw rate = (v_r - v_l) / (factor * track). >= 1;
  // must stay 1 for a differential drive.
  double skid_track_factor = 1.0;

  // Covariance model (1-sigma values).
  double vx_sigma_floor_mps = 0.005;      // noise floor of vx
  double vyaw_sigma_floor_radps = 0.005;  // noise floor of vyaw
  double slip_fraction = 0.02;            // relative speed error of each side
  // Skid steer: extra yaw-rate variance per m/s of |v_r - v_l| ((rad/s)^2 / (m/s)),
  // for the lateral scrubbing a turn needs.
  double skid_yaw_variance_per_mps = 0.0;

  // Two sample sets further apart than this are not differenced (re-seed).
  TimeNs max_gap_ns = 500'000'000;
};

// True when usable; otherwise *error names the field, the value and the fix.
bool validate_config(const WheelOdometryConfig& config, std::string* error);

}  // namespace rtfuse::drivers
