#include "runtime/config/hardware_config_loader.hpp"

#include <filesystem>
#include <string>
#include <string_view>

#include "drivers/camera/camera_modes.hpp"
#include "hal/linux/termios_serial_port.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::config {
namespace {

bool valid_cob_id(std::int64_t v) { return v >= 1 && v <= 0x7FF; }

void read_backend(const Section& s, HardwareConfig& hw, const std::string& config_file) {
  s.reject_unknown({"backend", "scenario"});
  std::string backend;
  if (s.read("backend", backend)) {
    if (backend == "none") {
      hw.backend = HalBackend::kNone;
    } else if (backend == "linux") {
      hw.backend = HalBackend::kLinux;
    } else if (backend == "sim") {
      hw.backend = HalBackend::kSim;
    } else {
      s.value_error("backend", "must be one of none, linux, sim, got " + in_quotes(backend));
    }
  }
  std::string scenario;
  if (s.read("scenario", scenario)) {
    if (scenario.empty()) {
      s.value_error("scenario", "must not be empty");
    } else {
      // Relative to the config file, so a config and its scenarios move together.
      std::filesystem::path p(scenario);
      if (p.is_relative() && !config_file.empty() && config_file.front() != '<') {
        p = std::filesystem::path(config_file).parent_path() / p;
      }
      hw.scenario = p.lexically_normal().string();
    }
  }
  if (hw.backend == HalBackend::kSim && hw.scenario.empty()) {
    s.table_error(s.key("scenario"), "backend \"sim\" needs a scenario file (scenario = \"scenarios/demo.toml\")");
  }
  if (hw.backend != HalBackend::kSim && !hw.scenario.empty()) {
    s.key_error("scenario", "only used with backend = \"sim\"");
  }
}

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

void read_attitude(const Section& s, AttitudeSection& a) {
  s.reject_unknown({"algorithm", "beta", "zeta", "kp", "ki"});
  std::string alg;
  if (s.read("algorithm", alg)) {
    if (alg == "madgwick") {
      a.algorithm = AttitudeAlgorithmConfig::kMadgwick;
    } else if (alg == "mahony") {
      a.algorithm = AttitudeAlgorithmConfig::kMahony;
    } else {
      s.value_error("algorithm", "must be madgwick or mahony, got " + in_quotes(alg));
    }
  }
  const bool madgwick = a.algorithm == AttitudeAlgorithmConfig::kMadgwick;
  for (std::string_view k : {"beta", "zeta"}) {
    if (!madgwick && s.has(k)) s.key_error(k, "only used with algorithm = \"madgwick\"");
  }
  for (std::string_view k : {"kp", "ki"}) {
    if (madgwick && s.has(k)) s.key_error(k, "only used with algorithm = \"mahony\"");
  }
  read_number(s, "beta", a.beta, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "zeta", a.zeta, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "kp", a.kp, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "ki", a.ki, non_negative_finite, "must be >= 0 and finite");
}

void read_mpu(const Section& s, MpuSection& m) {
  s.reject_unknown({"device", "address", "model", "sample_rate_divider", "dlpf", "gyro_range", "accel_range",
                    "data_ready_chip", "data_ready_line", "poll_rate", "frame", "frozen_reads", "gyro_noise",
                    "accel_noise", "attitude"});
  m.enabled = true;
  s.read_name("device", m.device);
  read_int(s, "address", m.address, 0x08, 0x77);
  std::string model;
  if (s.read("model", model)) {
    if (model == "auto") {
      m.model = MpuModelConfig::kAuto;
    } else if (model == "mpu6050") {
      m.model = MpuModelConfig::kMpu6050;
    } else if (model == "mpu6500") {
      m.model = MpuModelConfig::kMpu6500;
    } else if (model == "mpu9250") {
      m.model = MpuModelConfig::kMpu9250;
    } else {
      s.value_error("model", "must be one of auto, mpu6050, mpu6500, mpu9250, got " + in_quotes(model));
    }
  }
  read_int(s, "sample_rate_divider", m.sample_rate_divider, 0, 255);
  read_int(s, "dlpf", m.dlpf, 0, 6);
  std::int64_t v = 0;
  if (s.read("gyro_range", v)) {
    if (v != 250 && v != 500 && v != 1000 && v != 2000) {
      s.value_error("gyro_range", "must be 250, 500, 1000 or 2000 deg/s, got " + std::to_string(v));
    } else {
      m.gyro_range_dps = static_cast<int>(v);
    }
  }
  if (s.read("accel_range", v)) {
    if (v != 2 && v != 4 && v != 8 && v != 16) {
      s.value_error("accel_range", "must be 2, 4, 8 or 16 g, got " + std::to_string(v));
    } else {
      m.accel_range_g = static_cast<int>(v);
    }
  }
  const bool chip = s.read_name("data_ready_chip", m.data_ready_chip);
  read_int(s, "data_ready_line", m.data_ready_line, 0, 1023);
  if (chip != s.has("data_ready_line")) {
    s.key_error(chip ? "data_ready_chip" : "data_ready_line",
                "data_ready_chip and data_ready_line go together: give both, or neither to poll at poll_rate");
  }
  if (chip && s.has("poll_rate")) s.key_error("poll_rate", "only used without a data-ready line");
  read_number(s, "poll_rate", m.poll_rate_hz, [](double r) { return r > 0 && r <= 1000; },
              "must be > 0 and <= 1000 Hz");
  s.read_name("frame", m.frame);
  read_int(s, "frozen_reads", m.frozen_reads, 2, 100000);
  read_number(s, "gyro_noise", m.gyro_noise_rad_s, positive_finite, "must be > 0 rad/s and finite");
  read_number(s, "accel_noise", m.accel_noise_mps2, positive_finite, "must be > 0 m/s^2 and finite");
  read_attitude(Section(section_table(s, "attitude"), s.key("attitude"), s.diag()), m.attitude);
}

// The sensor fed by a driver, checked against what the driver produces.
int find_source(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sites, SensorSource source,
                std::string_view source_name, est::SensorKind kind, std::string_view kind_name, bool driver_configured,
                std::string_view driver_section) {
  int found = -1;
  for (int i = 0; i < cfg.num_sensors && i < static_cast<int>(sites.size()); ++i) {
    const SensorConfig& sc = cfg.sensors[static_cast<std::size_t>(i)];
    // Another instance's sensor on the same driver shares the first one's ring.
    if (sc.source != source || sensor_input(cfg, i) != i) continue;
    const SensorSite& site = sites[static_cast<std::size_t>(i)];
    const std::string key = site.key + ".source";
    if (found >= 0) {
      root.diag().add(site.where, key, "a second sensor with source = " + in_quotes(source_name) + " (also " +
                                           sites[static_cast<std::size_t>(found)].key + ")");
      continue;
    }
    if (sc.params.kind != kind) {
      root.diag().add(site.where, site.key + ".type",
                      "source " + in_quotes(source_name) + " produces type " + in_quotes(kind_name));
    }
    if (!driver_configured) {
      root.diag().add(site.where, key, "source " + in_quotes(source_name) + " needs a [" + std::string(driver_section) +
                                           "] section");
    }
    found = i;
  }
  if (found < 0 && driver_configured) {
    const toml::node* n = root.find(driver_section);
    root.diag().add(n ? n->source() : toml::source_region{}, std::string(driver_section),
                    "no [[sensor]] with source = " + in_quotes(source_name) + " fuses it");
  }
  return found;
}

// A path relative to the config file, so a config and its files move together.
std::string relative_to_config(const std::string& path, const std::string& config_file) {
  std::filesystem::path p(path);
  if (p.is_relative() && !config_file.empty() && config_file.front() != '<') {
    p = std::filesystem::path(config_file).parent_path() / p;
  }
  return p.lexically_normal().string();
}

void read_camera(const Section& s, CameraSection& c, const std::string& config_file) {
  s.reject_unknown({"device", "calibration", "serial", "resolution", "fps", "buffers", "pool_frames", "frame",
                    "reopen_backoff", "reopen_backoff_max", "info_channel", "preview_channel", "preview_rate",
                    "preview_downscale"});
  s.require({"calibration"});
  c.enabled = true;
  s.read_name("device", c.device);
  std::string calibration;
  if (s.read("calibration", calibration)) {
    if (calibration.empty()) {
      s.value_error("calibration", "must name the camera's factory calibration file (SN<serial>.conf)");
    } else {
      c.calibration_file = relative_to_config(calibration, config_file);
    }
  }
  read_int(s, "serial", c.serial, 0, std::int64_t{1} << 40);
  s.read_name("resolution", c.resolution);
  read_int(s, "fps", c.fps, 1, 1000);
  drivers::CameraMode mode;
  std::string why;
  if (!drivers::find_camera_mode(c.resolution.view(), c.fps, &mode, &why)) {
    s.value_error(s.has("fps") ? "fps" : "resolution", why);
  }
  read_int(s, "buffers", c.buffers, 2, hal::kMaxVideoBuffers);
  read_int(s, "pool_frames", c.pool_frames, 2, 16);
  s.read_name("frame", c.frame);
  read_number(s, "reopen_backoff", c.reopen_backoff_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "reopen_backoff_max", c.reopen_backoff_max_s, positive_finite, "must be > 0 s and finite");
  if (c.reopen_backoff_max_s < c.reopen_backoff_s) {
    s.value_error("reopen_backoff_max", "must be >= reopen_backoff");
  }
  s.read_name("info_channel", c.info_channel);
  s.read_name("preview_channel", c.preview_channel);
  read_number(s, "preview_rate", c.preview_rate_hz, non_negative_finite, "must be >= 0 Hz and finite (0: no preview)");
  read_int(s, "preview_downscale", c.preview_downscale, 1, 16);
}

void read_vo(const Section& s, VoSection& v) {
  s.reject_unknown({"half_resolution", "ransac_iterations", "inlier_threshold", "min_inliers", "bucket_size",
                    "bucket_max", "max_interval", "max_speed", "max_turn_rate", "covariance_scale",
                    "min_linear_sigma", "min_angular_sigma"});
  v.enabled = true;
  s.read("half_resolution", v.half_resolution);
  read_int(s, "ransac_iterations", v.ransac_iterations, 10, 5000);
  read_number(s, "inlier_threshold", v.inlier_threshold_px, [](double x) { return x > 0 && x <= 20; },
              "must be > 0 and <= 20 px");
  read_int(s, "min_inliers", v.min_inliers, 6, 1000);
  read_int(s, "bucket_size", v.bucket_size_px, 8, 1000);
  read_int(s, "bucket_max", v.bucket_max, 1, 64);
  read_number(s, "max_interval", v.max_interval_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "max_speed", v.max_speed_mps, positive_finite, "must be > 0 m/s and finite");
  read_number(s, "max_turn_rate", v.max_turn_rate_rad_s, positive_finite, "must be > 0 rad/s and finite");
  read_number(s, "covariance_scale", v.covariance_scale, positive_finite, "must be > 0 and finite");
  read_number(s, "min_linear_sigma", v.min_linear_sigma_mps, non_negative_finite, "must be >= 0 m/s and finite");
  read_number(s, "min_angular_sigma", v.min_angular_sigma_rad_s, non_negative_finite,
              "must be >= 0 rad/s and finite");
}

void read_gnss(const Section& s, GnssSection& g) {
  s.reject_unknown({"device", "baud", "protocol", "use_rmc", "use_gst", "latency", "silent_after", "reopen_backoff",
                    "reopen_backoff_max"});
  g.enabled = true;
  s.read_name("device", g.device);
  read_int(s, "baud", g.baud, 1, 4'000'000);
  if (!hal::TermiosSerialPort::supports(g.baud)) {
    s.value_error("baud", "must be one of " + hal::TermiosSerialPort::supported_bauds() + ", got " +
                              std::to_string(g.baud));
  }
  std::string protocol;
  if (s.read("protocol", protocol)) {
    if (protocol == "ubx") {
      g.protocol = GnssProtocolConfig::kUbx;
    } else if (protocol == "nmea") {
      g.protocol = GnssProtocolConfig::kNmea;
    } else {
      s.value_error("protocol", "must be ubx (u-blox NAV-PVT) or nmea (GGA/RMC/GST), got " + in_quotes(protocol));
    }
  }
  s.read("use_rmc", g.use_rmc);
  s.read("use_gst", g.use_gst);
  if (g.protocol == GnssProtocolConfig::kUbx) {
    for (std::string_view k : {"use_rmc", "use_gst"}) {
      if (s.has(k)) s.key_error(k, "only valid with protocol = \"nmea\"");
    }
  }
  read_number(s, "latency", g.latency_s, [](double v) { return v >= 0 && v <= 2.0; }, "must be >= 0 and <= 2 s");
  read_number(s, "silent_after", g.silent_after_s, [](double v) { return v >= 0.2 && v <= 60.0; },
              "must be >= 0.2 and <= 60 s");
  read_number(s, "reopen_backoff", g.reopen_backoff_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "reopen_backoff_max", g.reopen_backoff_max_s, positive_finite, "must be > 0 s and finite");
  if (g.reopen_backoff_max_s < g.reopen_backoff_s) {
    s.value_error("reopen_backoff_max", "must be >= reopen_backoff");
  }
}

}  // namespace

void read_hardware(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sites) {
  HardwareConfig& hw = cfg.hardware;
  Diagnostics& d = root.diag();
  read_backend(Section(section_table(root, "hardware"), "hardware", d), hw, cfg.source);
  const toml::table* can = section_table(root, "can");
  if (can) read_can(Section(can, "can", d), hw.can);
  const toml::table* wheels = section_table(root, "wheel_odometry");
  if (wheels) {
    read_wheel_odometry(Section(wheels, "wheel_odometry", d), hw.wheel_odometry);
    if (!can) Section(wheels, "wheel_odometry", d).table_error("wheel_odometry", "needs a [can] section with the wheel encoders");
  }
  const toml::table* mpu = section_table(root, "mpu");
  if (mpu) read_mpu(Section(mpu, "mpu", d), hw.mpu);
  const toml::table* camera = section_table(root, "camera");
  if (camera) read_camera(Section(camera, "camera", d), hw.camera, cfg.source);
  const toml::table* vo = section_table(root, "vo");
  if (vo) {
    read_vo(Section(vo, "vo", d), hw.vo);
    if (!camera) Section(vo, "vo", d).table_error("vo", "needs a [camera] section: the odometry runs on its frames");
  }
  const toml::table* gnss = section_table(root, "gnss");
  if (gnss) read_gnss(Section(gnss, "gnss", d), hw.gnss);
  if ((can || mpu || camera || gnss) && hw.backend == HalBackend::kNone) {
    const char* name = can ? "can" : (mpu ? "mpu" : (camera ? "camera" : "gnss"));
    const Section s(can ? can : (mpu ? mpu : (camera ? camera : gnss)), name, d);
    s.table_error("hardware.backend", std::string("[") + name +
                                          "] needs hardware.backend = \"linux\" (real devices) or \"sim\"");
  }
  hw.wheel_sensor = find_source(root, cfg, sites, SensorSource::kWheelOdometry, "wheel_odometry", est::SensorKind::kTwist,
                                "twist", wheels != nullptr, "wheel_odometry");
  hw.mpu_sensor = find_source(root, cfg, sites, SensorSource::kMpu, "mpu", est::SensorKind::kImu, "imu", mpu != nullptr, "mpu");
  hw.vo_sensor = find_source(root, cfg, sites, SensorSource::kStereoVo, "stereo_vo", est::SensorKind::kTwist, "twist",
                             vo != nullptr, "vo");
  hw.gnss_sensor = find_source(root, cfg, sites, SensorSource::kGnss, "gnss", est::SensorKind::kNavSatFix, "navsat",
                               gnss != nullptr, "gnss");
}

}  // namespace rtfuse::config
