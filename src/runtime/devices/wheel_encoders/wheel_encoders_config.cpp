#include "runtime/devices/wheel_encoders/wheel_encoders_config.hpp"

#include <string>

#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

bool valid_cob_id(std::int64_t v) { return v >= 1 && v <= 0x7FF; }

void read_node(const Section& s, CanNodeSection& n) {
  s.reject_unknown({"node_id", "side", "sign", "tpdo_cob_id", "position_offset", "position_bits",
                    "position_signed"});
  s.require({"node_id", "side"});
  read_int(s, "node_id", n.node_id, 1, 127);
  std::string side;
  if (s.read("side", side)) {
    if (side == "left") {
      n.side = WheelSideConfig::kLeft;
    } else if (side == "right") {
      n.side = WheelSideConfig::kRight;
    } else {
      s.value_error("side", "must be left or right, got " + in_quotes(side));
    }
  }
  std::int64_t sign = n.sign;
  if (s.read("sign", sign)) {
    if (sign != 1 && sign != -1) {
      s.value_error("sign", "must be 1 or -1, got " + std::to_string(sign));
    } else {
      n.sign = static_cast<int>(sign);
    }
  }
  std::int64_t cob = 0;
  if (s.read("tpdo_cob_id", cob)) {
    if (!valid_cob_id(cob)) {
      s.value_error("tpdo_cob_id", "must be an 11-bit COB-ID 0x001..0x7FF, got " + std::to_string(cob));
    } else {
      n.tpdo_cob_id = static_cast<std::uint32_t>(cob);
    }
  }
  read_int(s, "position_offset", n.position_offset, 0, 7);
  std::int64_t bits = n.position_bits;
  if (s.read("position_bits", bits)) {
    if (bits != 8 && bits != 16 && bits != 24 && bits != 32) {
      s.value_error("position_bits", "must be 8, 16, 24 or 32, got " + std::to_string(bits));
    } else {
      n.position_bits = static_cast<std::uint8_t>(bits);
    }
  }
  if (n.position_offset + n.position_bits / 8 > 8) {
    s.value_error(s.has("position_offset") ? "position_offset" : "position_bits",
                  "position_offset + position_bits/8 must fit the 8 data bytes of a CAN frame, got " +
                      std::to_string(n.position_offset) + " + " + std::to_string(n.position_bits / 8));
  }
  s.read("position_signed", n.position_signed);
}

void read_can(const Section& s, CanSection& can) {
  s.reject_unknown({"interface", "sync_cob_id", "heartbeat_timeout", "tpdo_timeout_syncs", "stuck_time",
                    "max_wheel_speed", "node"});
  can.enabled = true;
  s.read_name("interface", can.interface);
  std::int64_t sync = 0;
  if (s.read("sync_cob_id", sync)) {
    if (!valid_cob_id(sync)) {
      s.value_error("sync_cob_id", "must be an 11-bit COB-ID 0x001..0x7FF, got " + std::to_string(sync));
    } else {
      can.sync_cob_id = static_cast<std::uint32_t>(sync);
    }
  }
  read_number(s, "heartbeat_timeout", can.heartbeat_timeout_s, non_negative_finite,
              "must be >= 0 s and finite (0 disables heartbeat supervision)");
  read_int(s, "tpdo_timeout_syncs", can.tpdo_timeout_syncs, 1, 1000);
  read_number(s, "stuck_time", can.stuck_time_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "max_wheel_speed", can.max_wheel_speed_mps, positive_finite, "must be > 0 m/s and finite");
  bool left = false, right = false;
  for_each_table(s, "node", kMaxWheelNodes, [&](const Section& n, bool fits) {
    CanNodeSection node;
    read_node(n, node);
    for (int j = 0; j < can.num_nodes; ++j) {
      if (can.nodes[static_cast<std::size_t>(j)].node_id == node.node_id) {
        n.value_error("node_id", "node " + std::to_string(node.node_id) + " is also " + s.key("node") + "[" +
                                     std::to_string(j) + "]");
        break;
      }
    }
    if (node.tpdo_cob_id != 0 && node.tpdo_cob_id == can.sync_cob_id) {
      n.value_error("tpdo_cob_id", "equals sync_cob_id");
    }
    left = left || node.side == WheelSideConfig::kLeft;
    right = right || node.side == WheelSideConfig::kRight;
    if (fits) can.nodes[static_cast<std::size_t>(can.num_nodes++)] = node;
  });
  if (!left || !right) {
    s.table_error(s.key("node"), "needs at least one [[can.node]] with side = \"left\" and one with side = \"right\"");
  }
}

void read_wheel_odometry(const Section& s, WheelOdometrySection& w) {
  s.reject_unknown({"kinematics", "track_width", "wheel_radius", "counts_per_rev", "gear_ratio",
                    "skid_track_factor", "speed_noise", "yaw_rate_noise", "slip", "lateral_noise",
                    "raw_channel", "raw_rate"});
  s.require({"track_width", "wheel_radius", "counts_per_rev"});
  std::string k;
  if (s.read("kinematics", k)) {
    if (k == "differential") {
      w.kinematics = KinematicsConfig::kDifferential;
    } else if (k == "skid_steer") {
      w.kinematics = KinematicsConfig::kSkidSteer;
    } else {
      s.value_error("kinematics", "must be differential or skid_steer, got " + in_quotes(k));
    }
  }
  read_number(s, "track_width", w.track_width_m, positive_finite, "must be > 0 m and finite");
  read_number(s, "wheel_radius", w.wheel_radius_m, positive_finite, "must be > 0 m and finite");
  read_number(s, "counts_per_rev", w.counts_per_rev, positive_finite, "must be > 0 and finite");
  read_number(s, "gear_ratio", w.gear_ratio, positive_finite, "must be > 0 and finite");
  read_number(s, "skid_track_factor", w.skid_track_factor, [](double v) { return v >= 1 && v < 10; },
              "must be >= 1 and < 10 (effective track / track width)");
  if (w.kinematics == KinematicsConfig::kDifferential && s.has("skid_track_factor") && w.skid_track_factor != 1.0) {
    s.key_error("skid_track_factor", "only used with kinematics = \"skid_steer\"");
  }
  read_number(s, "speed_noise", w.speed_noise_mps, non_negative_finite, "must be >= 0 m/s and finite");
  read_number(s, "yaw_rate_noise", w.yaw_rate_noise_rad_s, non_negative_finite, "must be >= 0 rad/s and finite");
  read_number(s, "slip", w.slip, [](double v) { return v >= 0 && v < 1; }, "must be >= 0 and < 1");
  read_number(s, "lateral_noise", w.lateral_noise_mps, positive_finite, "must be > 0 m/s and finite");
  s.read_name("raw_channel", w.raw_channel);
  read_number(s, "raw_rate", w.raw_rate_hz, [](double v) { return v >= 0 && v <= 1000; },
              "must be >= 0 and <= 1000 Hz (0 disables)");
  if (w.speed_noise_mps == 0 && w.slip == 0) {
    s.key_error("speed_noise", "speed_noise and slip are both 0: the twist would claim a zero variance");
  }
}

}  // namespace

void read_wheel_encoders_config(const Section& root, RuntimeConfig& cfg) {
  HardwareConfig& hw = cfg.hardware;
  Diagnostics& d = root.diag();
  const toml::table* can = section_table(root, "can");
  if (can) read_can(Section(can, "can", d), hw.can);
  const toml::table* wheels = section_table(root, "wheel_odometry");
  if (wheels) {
    read_wheel_odometry(Section(wheels, "wheel_odometry", d), hw.wheel_odometry);
    if (!can) Section(wheels, "wheel_odometry", d).table_error("wheel_odometry", "needs a [can] section with the wheel encoders");
  }
}

}  // namespace rtfuse::config
