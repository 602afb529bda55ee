#pragma once
// [can], [[can.node]] and [wheel_odometry]: the CANopen (CiA 406) wheel
// encoders and the odometry they feed, as the TOML describes them. Plain
// values; wheel_encoder_device.cpp turns them into the drivers' configs.
// Schema: docs/configuration.md.
#include <array>
#include <cstdint>

#include "runtime/config/name.hpp"

namespace rtfuse {

enum class WheelSideConfig : std::uint8_t { kLeft, kRight };
enum class KinematicsConfig : std::uint8_t { kDifferential, kSkidSteer };

constexpr int kMaxWheelNodes = 8;

struct CanNodeSection {
  std::uint8_t node_id = 1;
  WheelSideConfig side = WheelSideConfig::kLeft;
  int sign = 1;                      // -1 for the mirrored motor
  std::uint32_t tpdo_cob_id = 0;     // 0: TPDO1 = 0x180 + node_id
  std::uint8_t position_offset = 0;  // first byte of the position in the TPDO
  std::uint8_t position_bits = 32;   // 8, 16, 24 or 32
  bool position_signed = false;
};

struct CanSection {
  bool enabled = false;
  Name interface{"can0"};
  std::uint32_t sync_cob_id = 0x080;
  double heartbeat_timeout_s = 0.5;  // 0: no heartbeat supervision
  int tpdo_timeout_syncs = 5;
  double stuck_time_s = 0.5;
  double max_wheel_speed_mps = 5.0;  // beyond this a counter step is a glitch
  std::array<CanNodeSection, kMaxWheelNodes> nodes{};
  int num_nodes = 0;
};

struct WheelOdometrySection {
  KinematicsConfig kinematics = KinematicsConfig::kDifferential;
  double track_width_m = 0.5;
  double wheel_radius_m = 0.1;
  double counts_per_rev = 4096;
  double gear_ratio = 1.0;
  double skid_track_factor = 1.0;
  double speed_noise_mps = 0.01;
  double yaw_rate_noise_rad_s = 0.02;
  double slip = 0.02;              // 1-sigma fractional speed error
  double lateral_noise_mps = 0.01; // vy: the non-holonomic constraint, held loosely
  Name raw_channel{"rtfuse/wheel_odometry"};  // dead-reckoned odometry_t
  double raw_rate_hz = 50.0;                  // 0: not published
};

}  // namespace rtfuse
