#include "runtime/config/config_loader.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geometry/rotation.hpp"
#include "runtime/devices/device_config.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/config/toml_reader.hpp"

namespace rtfuse {
namespace {

using config::Diagnostics;
using config::Section;
using config::fmt;
using config::for_each_table;
using config::in_quotes;
using config::non_negative_finite;
using config::positive;
using config::positive_finite;
using config::read_covariance;
using config::read_fixed;
using config::read_int;
using config::read_number;
using config::section_table;
using config::type_name;
using est::StateMatrix;
using est::UpdateMask;

constexpr std::array<std::string_view, est::kStateSize> kStateNames = {
    "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
    "vroll", "vpitch", "vyaw", "ax", "ay", "az"};
constexpr const char* kStateList = "x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az";

// robot_localization's ekf defaults, so a config without the key behaves
// exactly like an ekf.yaml without it.
constexpr std::array<double, est::kStateSize> kDefaultProcessNoise = {
    0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};
constexpr double kDefaultInitialVariance = 1e-9;

// A frame constraint names the key the user wrote, so prefer that one when
// the other side of the comparison is a default.
void frames_must_differ(const Section& s, std::string_view a, const Name& va, std::string_view b,
                        const Name& vb) {
  if (va != vb) return;
  const std::string_view at = s.has(b) ? b : a;
  const std::string_view other = at == b ? a : b;
  s.value_error(at, "must differ from " + std::string(other) + " (both " + in_quotes(va.view()) + ")");
}

// The [filter] keys an [[instance]] may give as well (the loop's rate and
// the frame names are the process's).
void read_filter_params(const Section& s, est::FilterParams& f) {
  read_number(s, "sensor_timeout", f.sensor_timeout_s, positive_finite, "must be > 0 s and finite");
  s.read("two_d_mode", f.two_d_mode);
  read_covariance(s, "process_noise_covariance", f.process_noise);
  read_covariance(s, "initial_estimate_covariance", f.initial_covariance);
  s.read("dynamic_process_noise_covariance", f.dynamic_process_noise);
  if (const auto x0 = read_fixed(s, "initial_state", est::kStateSize, kStateList)) {
    f.has_initial_state = true;
    f.initial_state = Eigen::Map<const est::StateVector>(x0->data());
  }
  read_number(s, "max_variance", f.max_variance, positive, "must be > 0");
  s.read("smooth_lagged_data", f.smooth_lagged_data);
  const bool history_ok = read_number(s, "history_length", f.history_length_s, non_negative_finite,
                                      "must be >= 0 s and finite");
  if (f.smooth_lagged_data && !(f.history_length_s > 0) && (history_ok || !s.has("history_length"))) {
    const std::string_view at = s.has("history_length") ? "history_length" : "smooth_lagged_data";
    s.diag().add(s.value_where(at), s.key("history_length"),
                 "must be > 0 s when smooth_lagged_data is true, got " + fmt(f.history_length_s));
  }
  read_number(s, "gravitational_acceleration", f.gravity, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "yaw_conflict_gate", f.yaw_conflict_gate_sigma, positive, "must be > 0");
}

// An instance's name is a channel prefix (rtfuse/<name>/odometry) and a key
// of the replay's JSON: short, lower case, no separators.
bool read_instance_name(const Section& s, Name& out) {
  std::string name;
  if (!s.read("name", name)) return false;
  const bool ok = !name.empty() && name.size() <= 15 &&
                  std::all_of(name.begin(), name.end(), [](char c) {
                    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
                  });
  if (!ok) {
    s.value_error("name", "must be 1 to 15 characters of a-z, 0-9 and _ (it names the instance's channels, "
                          "rtfuse/<name>/...), got " + in_quotes(name));
    return false;
  }
  out = Name(name);
  return true;
}

void read_filter(const Section& s, RuntimeConfig& cfg) {
  s.reject_unknown({"name", "frequency", "sensor_timeout", "two_d_mode", "world_frame", "odom_frame",
                    "base_link_frame", "map_frame", "process_noise_covariance",
                    "initial_estimate_covariance", "dynamic_process_noise_covariance",
                    "initial_state", "max_variance", "smooth_lagged_data", "history_length",
                    "gravitational_acceleration", "yaw_conflict_gate"});
  est::FilterParams& f = cfg.filter;
  read_number(s, "frequency", cfg.rate_hz, [](double v) { return v > 0 && v <= 10000; },
              "must be > 0 and <= 10000 Hz");
  f.sensor_timeout_s = 1.0 / cfg.rate_hz;
  read_instance_name(s, cfg.instances[0].name);

  s.read_name("odom_frame", cfg.odom_frame);
  s.read_name("base_link_frame", cfg.base_link_frame);
  s.read_name("map_frame", cfg.map_frame);
  cfg.world_frame = cfg.odom_frame;
  if (s.read_name("world_frame", cfg.world_frame) && cfg.world_frame != cfg.odom_frame &&
      cfg.world_frame != cfg.map_frame) {
    s.value_error("world_frame", "must equal odom_frame (" + in_quotes(cfg.odom_frame.view()) +
                                     ") or map_frame (" + in_quotes(cfg.map_frame.view()) + "), got " +
                                     in_quotes(cfg.world_frame.view()));
  }
  // robot_localization refuses the same name for two of these; base_link
  // differing from both also makes it differ from world_frame.
  frames_must_differ(s, "odom_frame", cfg.odom_frame, "base_link_frame", cfg.base_link_frame);
  frames_must_differ(s, "map_frame", cfg.map_frame, "base_link_frame", cfg.base_link_frame);
  frames_must_differ(s, "odom_frame", cfg.odom_frame, "map_frame", cfg.map_frame);

  f.process_noise = Eigen::Map<const est::StateVector>(kDefaultProcessNoise.data()).asDiagonal();
  f.initial_covariance = StateMatrix::Identity() * kDefaultInitialVariance;
  read_filter_params(s, f);
}

void read_realtime(const Section& s, RealtimeConfig& rt) {
  s.reject_unknown({"lock_memory", "priority", "io_priority", "cpu", "require"});
  s.read("lock_memory", rt.lock_memory);
  read_int(s, "priority", rt.priority, 0, 99);
  read_int(s, "io_priority", rt.io_priority, 0, 98);
  if (rt.io_priority > 0 && rt.io_priority >= rt.priority) {
    s.value_error("io_priority", "must be below priority (" + std::to_string(rt.priority) + "), got " +
                                     std::to_string(rt.io_priority) +
                                     ": the loop must preempt the threads that feed it");
  }
  read_int(s, "cpu", rt.cpu, -1, 1023);  // CPU_SETSIZE
  s.read("require", rt.require);
}

void read_lcm(const Section& s, RuntimeConfig& cfg) {
  s.reject_unknown({"url", "max_message_bytes", "max_stamp_ahead"});
  read_int(s, "max_message_bytes", cfg.lcm_max_message_bytes, 256, 1 << 20);
  double ahead_s = static_cast<double>(cfg.lcm_max_stamp_ahead_ns) / 1e9;
  if (read_number(s, "max_stamp_ahead", ahead_s, [](double v) { return v >= 0.001 && v <= 3600.0; },
                  "must be 0.001 .. 3600 s")) {
    cfg.lcm_max_stamp_ahead_ns = static_cast<TimeNs>(std::llround(ahead_s * 1e9));
  }
  std::string& url_out = cfg.lcm_url;
  std::string url;
  if (!s.read("url", url)) return;
  const std::size_t sep = url.find("://");
  if (url.empty()) {
    s.value_error("url", "must not be empty");
  } else if (sep == std::string::npos || sep == 0) {
    // LCM picks the provider from "name://"; without it lcm_create fails at
    // start-up with a far less helpful message.
    s.value_error("url", "must be '<provider>://...' (udpm://, memq://, file://, ...), got " + in_quotes(url));
  } else {
    url_out = url;
  }
}

// A channel in use, remembered so later sections can report a collision.
struct ChannelUse {
  Name name;
  std::string key;
};

void read_publish(const Section& s, PublishConfig& p, std::vector<ChannelUse>& channels) {
  s.reject_unknown({"odometry_channel", "odometry_rate", "pose_channel", "pose_rate", "tf_channel",
                    "tf_rate", "state_channel", "state_rate", "diagnostics_channel",
                    "diagnostics_rate", "set_pose_channel", "accept_set_pose", "publish_tf"});
  const std::pair<std::string_view, Name*> names[] = {
      {"odometry_channel", &p.odometry_channel}, {"pose_channel", &p.pose_channel},
      {"tf_channel", &p.tf_channel},             {"state_channel", &p.state_channel},
      {"diagnostics_channel", &p.diagnostics_channel}, {"set_pose_channel", &p.set_pose_channel}};
  for (const auto& [k, name] : names) {
    s.read_name(k, *name);
    for (const ChannelUse& used : channels) {
      if (used.name == *name) {
        s.value_error(k, "channel " + in_quotes(name->view()) + " is also " + used.key);
        break;
      }
    }
    channels.push_back({*name, s.key(k)});
  }
  const std::pair<std::string_view, double*> rates[] = {
      {"odometry_rate", &p.odometry_rate_hz}, {"pose_rate", &p.pose_rate_hz},
      {"tf_rate", &p.tf_rate_hz},             {"state_rate", &p.state_rate_hz},
      {"diagnostics_rate", &p.diagnostics_rate_hz}};
  for (const auto& [k, rate] : rates) {
    read_number(s, k, *rate, [](double v) { return v >= 0 && v <= 10000; },
                "must be >= 0 and <= 10000 Hz (0 disables)");
  }
  s.read("publish_tf", p.publish_tf);
  s.read("accept_set_pose", p.accept_set_pose);
}

std::optional<est::SensorKind> parse_kind(std::string_view t) {
  if (t == "odometry") return est::SensorKind::kOdometry;
  if (t == "pose") return est::SensorKind::kPose;
  if (t == "twist") return est::SensorKind::kTwist;
  if (t == "imu") return est::SensorKind::kImu;
  if (t == "navsat") return est::SensorKind::kNavSatFix;
  return std::nullopt;
}

std::string_view kind_name(est::SensorKind k) {
  switch (k) {
    case est::SensorKind::kOdometry: return "odometry";
    case est::SensorKind::kPose: return "pose";
    case est::SensorKind::kTwist: return "twist";
    case est::SensorKind::kImu: return "imu";
    case est::SensorKind::kNavSatFix: return "navsat";
  }
  return "?";
}

// What each message type carries (nav_msgs/Odometry has no acceleration,
// sensor_msgs/Imu no position or linear velocity).
UpdateMask providable(est::SensorKind k) {
  switch (k) {
    case est::SensorKind::kOdometry: return est::kPoseMask | est::kTwistMask;
    case est::SensorKind::kPose: return est::kPoseMask;
    case est::SensorKind::kTwist: return est::kTwistMask;
    case est::SensorKind::kImu:
      return est::kOrientationMask | est::kAngularVelocityMask | est::kAccelerationMask;
    // A fix is a position: navsat_transform_node's odometry/gps has no
    // meaningful orientation or velocity.
    case est::SensorKind::kNavSatFix: return est::kPositionMask;
  }
  return 0;
}

std::string mask_names(UpdateMask m) {
  std::string out;
  for (int i = 0; i < est::kStateSize; ++i) {
    if (!est::mask_has(m, i)) continue;
    if (!out.empty()) out += ' ';
    out += kStateNames[static_cast<std::size_t>(i)];
  }
  return out;
}

std::optional<UpdateMask> read_mask(const Section& s, std::string_view k) {
  const toml::array* a = s.array(k);
  if (!a) return std::nullopt;
  if (a->size() != static_cast<std::size_t>(est::kStateSize)) {
    s.key_error(k, std::string("expected 15 booleans (") + kStateList + "), got " + std::to_string(a->size()));
    return std::nullopt;
  }
  UpdateMask mask = 0;
  bool ok = true;
  for (int i = 0; i < est::kStateSize; ++i) {
    const toml::node& e = *a->get(static_cast<std::size_t>(i));
    if (const auto* b = e.as_boolean()) {
      if (b->get()) mask |= est::mask_bit(i);
    } else {
      s.diag().add(e.source(), s.key(k) + "[" + std::to_string(i) + "]",
                   "expected boolean, got " + type_name(e.type()));
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  return mask;
}

constexpr std::string_view kNavsatKeys[] = {"frame",      "heading_imu",        "use_odometry_yaw",
                                            "magnetic_declination_radians", "yaw_offset", "zero_altitude",
                                            "datum",      "unknown_covariance", "max_jump", "max_speed"};

// navsat_transform_node's parameters on the sensor (robot_localization's
// names where it has them). The datum's heading needs a source: an IMU
// sensor, the filter's own yaw, or a configured datum.
void read_navsat(const Section& s, SensorConfig& c) {
  est::NavsatParams& n = c.params.navsat;
  if (s.has("frame")) s.read_name("frame", c.antenna_frame);
  if (s.has("heading_imu")) s.read_name("heading_imu", c.heading_imu);
  s.read("use_odometry_yaw", n.use_filter_yaw);
  const auto finite_angle = [](double v) { return std::isfinite(v) && std::fabs(v) <= 6.3; };
  read_number(s, "magnetic_declination_radians", n.magnetic_declination_rad, finite_angle,
              "must be finite, within ±2π rad");
  read_number(s, "yaw_offset", n.yaw_offset_rad, finite_angle, "must be finite, within ±2π rad");
  s.read("zero_altitude", n.zero_altitude);
  if (const auto d = read_fixed(s, "datum", 3, "latitude (deg) longitude (deg) yaw (rad)")) {
    n.manual_datum = true;
    n.datum = {(*d)[0], (*d)[1], 0.0};
    n.datum_yaw_rad = (*d)[2];
    if (!est::is_valid_geodetic(n.datum)) {
      s.key_error("datum", "latitude must be within ±90 and longitude within ±180 degrees, got " +
                               std::to_string((*d)[0]) + ", " + std::to_string((*d)[1]));
    } else if (!finite_angle(n.datum_yaw_rad)) {
      s.key_error("datum", "yaw must be finite, within ±2π rad");
    }
  }
  if (const auto v = read_fixed(s, "unknown_covariance", 2, "horizontal vertical (m²)")) {
    n.unknown_horizontal_variance = (*v)[0];
    n.unknown_vertical_variance = (*v)[1];
    if (!(positive_finite((*v)[0]) && positive_finite((*v)[1]))) {
      s.key_error("unknown_covariance", "both variances must be > 0 and finite (m²)");
    }
  }
  read_number(s, "max_jump", n.max_jump_m, positive_finite, "must be > 0 m and finite");
  read_number(s, "max_speed", n.max_speed_mps, non_negative_finite, "must be >= 0 m/s and finite");
  const int heading_sources = (c.heading_imu.empty() ? 0 : 1) + (n.use_filter_yaw ? 1 : 0) + (n.manual_datum ? 1 : 0);
  if (heading_sources == 0) {
    s.key_error("heading_imu", "the datum needs a heading: name an imu sensor (heading_imu), set "
                               "use_odometry_yaw = true, or give datum = [latitude, longitude, yaw]");
  } else if (heading_sources > 1) {
    s.key_error("heading_imu", "give one heading source: heading_imu, use_odometry_yaw or datum");
  }
}

constexpr std::string_view kStandstillKeys[] = {"standstill_from", "standstill_block", "standstill_time_constant",
                                                "standstill_speed", "standstill_yaw_rate"};

// An IMU's residual gyro bias from the wheels' standstills: the wheel
// sensor is named here and resolved once every sensor is known.
void read_standstill(const Section& s, SensorConfig& c) {
  if (s.has("standstill_from")) s.read_name("standstill_from", c.standstill_from);
  est::StandstillBiasParams& p = c.standstill;
  read_number(s, "standstill_block", p.block_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "standstill_time_constant", p.time_constant_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "standstill_speed", p.still_speed_mps, [](double v) { return v >= 0 && v <= 0.1; },
              "must be in [0, 0.1] m/s");
  read_number(s, "standstill_yaw_rate", p.still_yaw_rate, [](double v) { return v >= 0 && v <= 0.1; },
              "must be in [0, 0.1] rad/s");
  if (c.standstill_from.empty()) {
    for (std::string_view k : kStandstillKeys) {
      if (k != "standstill_from" && s.has(k)) s.key_error(k, "needs standstill_from (the wheel sensor to learn from)");
    }
    return;
  }
  const char* why = est::validate(p);
  if (why[0] != '\0') s.value_error("standstill_block", why);
}

struct SensorEntry {
  SensorConfig cfg;
  bool has_name = false;
  bool has_channel = false;
};

SensorEntry read_sensor(const Section& s) {
  s.reject_unknown({"name", "type", "channel", "source", "config", "differential", "relative", "queue_size",
                    "pose_rejection_threshold", "twist_rejection_threshold",
                    "linear_acceleration_rejection_threshold", "remove_gravitational_acceleration", "max_rate",
                    "frame", "heading_imu", "use_odometry_yaw", "magnetic_declination_radians", "yaw_offset",
                    "zero_altitude", "datum", "unknown_covariance", "max_jump", "max_speed", "standstill_from",
                    "standstill_block", "standstill_time_constant", "standstill_speed", "standstill_yaw_rate"});
  s.require({"name", "type"});
  SensorEntry e;
  est::SensorParams& p = e.cfg.params;
  e.has_name = s.read_name("name", e.cfg.name);
  std::string source = "lcm";
  if (s.read("source", source)) {
    // lcm, or a source of a registered device (devices/device_registry).
    const int id = find_device_source(source);
    if (source == "lcm") {
      e.cfg.source = kLcmSource;
    } else if (id >= 0) {
      e.cfg.source = static_cast<SensorSource>(id);
    } else {
      s.value_error("source", "must be one of " + device_source_names() + ", got " + in_quotes(source));
    }
  }
  // A driver-fed sensor has no channel; an LCM one needs it.
  if (source == "lcm") {
    s.require({"channel"});
    e.has_channel = s.read_name("channel", e.cfg.channel);
    read_number(s, "max_rate", e.cfg.max_rate_hz, [](double v) { return v > 0 && v <= 1e6; },
                "must be > 0 and <= 1e6 Hz");
  } else {
    for (std::string_view k : {"channel", "max_rate"}) {
      if (s.has(k)) s.key_error(k, "not used with source = " + in_quotes(source) + " (the driver feeds this sensor)");
    }
  }
  s.require({"config"});

  std::optional<est::SensorKind> kind;
  std::string type;
  if (s.read("type", type)) {
    kind = parse_kind(type);
    if (kind) {
      p.kind = *kind;
    } else {
      s.value_error("type", "must be one of odometry, pose, twist, imu, navsat, got " + in_quotes(type));
    }
  }

  const auto mask = read_mask(s, "config");
  if (mask) {
    p.update_mask = *mask;
    if (*mask == 0) s.key_error("config", "fuses nothing: at least one entry must be true");
  }
  if (mask && kind) {
    const UpdateMask extra = *mask & static_cast<UpdateMask>(~providable(*kind));
    if (extra) {
      int first = 0;
      while (!est::mask_has(extra, first)) ++first;
      s.diag().add(s.find("config")->as_array()->get(static_cast<std::size_t>(first))->source(),
                   s.key("config"),
                   "type " + in_quotes(kind_name(*kind)) + " cannot provide " + mask_names(extra) +
                       " (it provides " + mask_names(providable(*kind)) + ")");
    }
  }

  s.read("differential", p.differential);
  s.read("relative", p.relative);
  if (p.differential && p.relative) s.value_error("relative", "differential and relative cannot both be true");
  read_int(s, "queue_size", p.queue_size, 1, 1024);
  read_number(s, "pose_rejection_threshold", p.pose_rejection_threshold, positive, "must be > 0");
  read_number(s, "twist_rejection_threshold", p.twist_rejection_threshold, positive, "must be > 0");
  read_number(s, "linear_acceleration_rejection_threshold", p.linear_acceleration_rejection_threshold,
              positive, "must be > 0");
  s.read("remove_gravitational_acceleration", p.remove_gravitational_acceleration);
  if (kind && *kind != est::SensorKind::kImu) {
    for (std::string_view k : {"linear_acceleration_rejection_threshold", "remove_gravitational_acceleration"}) {
      if (s.has(k)) s.key_error(k, "only valid for type 'imu'");
    }
  }
  if (kind && *kind == est::SensorKind::kImu) {
    read_standstill(s, e.cfg);
  } else if (kind) {
    for (std::string_view k : kStandstillKeys) {
      if (s.has(k)) s.key_error(k, "only valid for type 'imu' (the gyro whose bias the wheels' standstills teach)");
    }
  }
  if (kind && *kind == est::SensorKind::kNavSatFix) {
    read_navsat(s, e.cfg);
  } else if (kind) {
    for (std::string_view k : kNavsatKeys) {
      if (s.has(k)) s.key_error(k, "only valid for type 'navsat'");
    }
  }
  return e;
}

// An IMU's standstill_from, by name among its instance's sensors: one whose
// samples carry the base's twist (odometry, twist).
void resolve_standstill(const Section& s, const RuntimeConfig& cfg, int first, const std::string& instance_words,
                        SensorConfig& c) {
  if (c.standstill_from.empty()) return;
  for (int j = first; j < cfg.num_sensors; ++j) {
    const SensorConfig& o = cfg.sensors[static_cast<std::size_t>(j)];
    if (o.name != c.standstill_from) continue;
    if (o.params.kind != est::SensorKind::kOdometry && o.params.kind != est::SensorKind::kTwist) {
      s.value_error("standstill_from", in_quotes(c.standstill_from.view()) + " is a " +
                                           in_quotes(kind_name(o.params.kind)) +
                                           " sensor: name the wheels' odometry or twist sensor");
      return;
    }
    int learners = 0;
    for (int i = 0; i < cfg.num_sensors; ++i) learners += cfg.sensors[static_cast<std::size_t>(i)].standstill_sensor >= 0;
    if (learners >= kMaxStandstillLearners) {
      s.key_error("standstill_from", "at most " + std::to_string(kMaxStandstillLearners) +
                                         " imu sensors with standstill_from in all instances");
      return;
    }
    c.standstill_sensor = j;
    return;
  }
  s.value_error("standstill_from", "no sensor" + instance_words + " is named " + in_quotes(c.standstill_from.view()));
}

// The [[sensor]] tables of one instance (the top level's for the first, an
// [[instance]]'s own for the others), appended to cfg.sensors. A sensor on
// the source of an earlier instance's sensor (the same channel, or the same
// driver) shares its ring: one message, one fusion per instance.
void read_sensors(const Section& parent, RuntimeConfig& cfg, const std::vector<ChannelUse>& publish, int instance,
                  std::vector<config::SensorSite>& sites) {
  const int first = cfg.num_sensors;
  const std::string instance_words =
      instance == 0 ? "" : " in instance " + in_quotes(cfg.instances[static_cast<std::size_t>(instance)].name.view());
  for_each_table(parent, "sensor", kMaxSensors - first, [&](const Section& s, bool fits) {
    SensorEntry e = read_sensor(s);
    e.cfg.instance = instance;
    for (int j = first; j < cfg.num_sensors && e.has_name; ++j) {
      if (cfg.sensors[static_cast<std::size_t>(j)].name == e.cfg.name) {
        s.value_error("name", "duplicate sensor name " + in_quotes(e.cfg.name.view()) + instance_words + " (also " +
                                  sites[static_cast<std::size_t>(j)].key + ")");
        break;
      }
    }
    bool channel_taken = false;
    for (int j = 0; j < cfg.num_sensors && e.has_channel; ++j) {
      const SensorConfig& o = cfg.sensors[static_cast<std::size_t>(j)];
      if (o.channel != e.cfg.channel) continue;
      if (o.instance == instance) {
        s.value_error("channel", "channel " + in_quotes(e.cfg.channel.view()) + " is also " +
                                     sites[static_cast<std::size_t>(j)].key + ".channel");
      } else if (o.params.kind != e.cfg.params.kind) {
        s.value_error("channel", "channel " + in_quotes(e.cfg.channel.view()) + " is " +
                                     sites[static_cast<std::size_t>(j)].key + " of type " +
                                     in_quotes(kind_name(o.params.kind)) +
                                     ": a sensor of another instance on it must have the same type");
      } else {
        e.cfg.input = sensor_input(cfg, j);
        break;
      }
      channel_taken = true;
      break;
    }
    for (const ChannelUse& used : publish) {
      if (!channel_taken && e.has_channel && used.name == e.cfg.channel) {
        s.value_error("channel", "channel " + in_quotes(e.cfg.channel.view()) + " is also " + used.key);
        break;
      }
    }
    // A driver's samples: shared with an earlier instance's sensor on it
    // (two of one instance are read_hardware's error).
    for (int j = 0; j < first && e.cfg.source != kLcmSource; ++j) {
      const SensorConfig& o = cfg.sensors[static_cast<std::size_t>(j)];
      if (o.source != e.cfg.source || sensor_input(cfg, j) != j) continue;
      if (o.params.kind != e.cfg.params.kind) {
        s.value_error("type", "the driver's samples are " + in_quotes(kind_name(o.params.kind)) + " (" +
                                  sites[static_cast<std::size_t>(j)].key + ")");
      }
      e.cfg.input = j;
      break;
    }
    if (e.cfg.params.kind == est::SensorKind::kNavSatFix) {
      int navsat = 0;
      for (int j = 0; j < cfg.num_sensors; ++j) {
        if (cfg.sensors[static_cast<std::size_t>(j)].params.kind == est::SensorKind::kNavSatFix) ++navsat;
      }
      if (navsat == kMaxNavsatSensors) {
        s.value_error("type", "at most " + std::to_string(kMaxNavsatSensors) + " navsat sensors in all instances");
      }
    }
    // Unnamed entries are still stored (the config is rejected anyway) so
    // that "also sensor[j]" indices match the file.
    if (fits) {
      sites.push_back({s.path(), s.where()});
      cfg.sensors[static_cast<std::size_t>(cfg.num_sensors++)] = e.cfg;
    }
  });
  // A navsat sensor's heading IMU, by name among its instance's sensors,
  // once they are all known.
  const toml::array* entries = config::table_array(parent, "sensor");
  int index = first;
  for (std::size_t i = 0; entries != nullptr && i < entries->size() && index < cfg.num_sensors; ++i) {
    const auto* t = entries->get(i)->as_table();
    if (t == nullptr) continue;
    const Section s(t, parent.key("sensor") + "[" + std::to_string(i) + "]", parent.diag());
    SensorConfig& c = cfg.sensors[static_cast<std::size_t>(index++)];
    resolve_standstill(s, cfg, first, instance_words, c);
    if (c.heading_imu.empty()) continue;
    for (int j = first; j < cfg.num_sensors && c.heading_sensor < 0; ++j) {
      const SensorConfig& o = cfg.sensors[static_cast<std::size_t>(j)];
      if (o.name != c.heading_imu) continue;
      // navsat_transform reads the IMU's orientation whether or not the
      // filter fuses its yaw (robot_localization's example fuses none).
      if (o.params.kind != est::SensorKind::kImu) {
        s.value_error("heading_imu", in_quotes(c.heading_imu.view()) + " is not an imu sensor");
        break;
      }
      c.heading_sensor = j;
    }
    const bool named = std::any_of(cfg.sensors.begin() + first, cfg.sensors.begin() + cfg.num_sensors,
                                   [&](const SensorConfig& o) { return o.name == c.heading_imu; });
    if (!named) s.value_error("heading_imu", "no sensor" + instance_words + " is named " + in_quotes(c.heading_imu.view()));
  }
}

constexpr std::string_view kInstanceRates[] = {"odometry_rate", "pose_rate", "state_rate", "tf_rate",
                                               "filtered_fix_rate"};

// [[instance]]: a further filter: its name, world frame, the [filter] keys
// it changes, its output rates, and its own [[instance.sensor]] tables.
void read_instance(const Section& s, RuntimeConfig& cfg, int k, std::vector<ChannelUse>& channels,
                   std::vector<config::SensorSite>& sites) {
  s.reject_unknown({"name", "world_frame", "sensor_timeout", "two_d_mode", "process_noise_covariance",
                    "initial_estimate_covariance", "dynamic_process_noise_covariance", "initial_state",
                    "max_variance", "smooth_lagged_data", "history_length", "gravitational_acceleration",
                    "yaw_conflict_gate", "odometry_rate", "pose_rate", "state_rate", "tf_rate", "filtered_fix_rate",
                    "sensor"});
  s.require({"name", "sensor"});
  InstanceConfig& in = cfg.instances[static_cast<std::size_t>(k)];
  in.filter = cfg.filter;
  in.world_frame = cfg.map_frame;
  if (read_instance_name(s, in.name)) {
    for (int j = 0; j < k; ++j) {
      if (cfg.instances[static_cast<std::size_t>(j)].name == in.name) {
        s.value_error("name", "instance name " + in_quotes(in.name.view()) + " is also " +
                                  (j == 0 ? std::string("the first instance's ([filter] name, default 'local')")
                                          : "instance[" + std::to_string(j - 1) + "].name"));
        break;
      }
    }
  }
  if (s.read_name("world_frame", in.world_frame) && in.world_frame != cfg.odom_frame &&
      in.world_frame != cfg.map_frame) {
    s.value_error("world_frame", "must equal odom_frame (" + in_quotes(cfg.odom_frame.view()) + ") or map_frame (" +
                                     in_quotes(cfg.map_frame.view()) + "), got " + in_quotes(in.world_frame.view()));
  }
  read_filter_params(s, in.filter);
  const PublishConfig& p = cfg.publish;
  in.odometry_rate_hz = p.odometry_rate_hz;
  in.pose_rate_hz = p.pose_rate_hz;
  in.state_rate_hz = p.state_rate_hz;
  in.tf_rate_hz = p.tf_rate_hz;
  double* const rates[] = {&in.odometry_rate_hz, &in.pose_rate_hz, &in.state_rate_hz, &in.tf_rate_hz,
                           &in.filtered_fix_rate_hz};
  for (std::size_t r = 0; r < std::size(kInstanceRates); ++r) {
    read_number(s, kInstanceRates[r], *rates[r], [](double v) { return v >= 0 && v <= 10000; },
                "must be >= 0 and <= 10000 Hz (0 disables)");
  }
  const std::string prefix = "rtfuse/" + std::string(in.name.view()) + "/";
  in.odometry_channel = Name(prefix + "odometry");
  in.pose_channel = Name(prefix + "pose");
  in.state_channel = Name(prefix + "state");
  in.filtered_fix_channel = Name(prefix + "gps/filtered");
  for (const Name* c : {&in.odometry_channel, &in.pose_channel, &in.state_channel, &in.filtered_fix_channel}) {
    for (const ChannelUse& used : channels) {
      if (used.name == *c) {
        s.value_error("name", "its channel " + in_quotes(c->view()) + " is also " + used.key);
        break;
      }
    }
    channels.push_back({*c, s.key("name") + " (its outputs)"});
  }
  const int before = cfg.num_sensors;
  read_sensors(s, cfg, channels, k, sites);
  if (cfg.num_sensors == before && s.has("sensor") && config::table_array(s, "sensor") != nullptr &&
      config::table_array(s, "sensor")->empty()) {
    s.key_error("sensor", "an instance needs at least one [[instance.sensor]]");
  }
}

void read_instances(const Section& root, RuntimeConfig& cfg, std::vector<ChannelUse>& channels,
                    std::vector<config::SensorSite>& sites) {
  cfg.instances[0].filtered_fix_channel = Name("rtfuse/gps/filtered");
  channels.push_back({cfg.instances[0].filtered_fix_channel, "the first instance's filtered fix"});
  for_each_table(root, "instance", kMaxInstances - 1, [&](const Section& s, bool fits) {
    if (!fits) return;
    read_instance(s, cfg, cfg.num_instances, channels, sites);
    ++cfg.num_instances;
  });
}

void read_static_transform(const Section& s, StaticTransformConfig& out) {
  s.reject_unknown({"parent", "child", "translation", "rpy", "quaternion"});
  s.require({"parent", "child", "translation"});
  const bool parent = s.read_name("parent", out.parent);
  if (s.read_name("child", out.child) && parent && out.parent == out.child) {
    s.value_error("child", "must differ from parent (both " + in_quotes(out.child.view()) + ")");
  }
  if (const auto t = read_fixed(s, "translation", 3, "x y z")) {
    out.parent_T_child.translation = Eigen::Vector3d((*t)[0], (*t)[1], (*t)[2]);
  }
  const bool has_rpy = s.has("rpy");
  const bool has_quaternion = s.has("quaternion");
  if (has_rpy && has_quaternion) {
    s.key_error("quaternion", "rpy and quaternion are both given: give exactly one");
    return;
  }
  if (!has_rpy && !has_quaternion) {
    s.table_error(s.key("rpy"), "missing rotation: give exactly one of rpy or quaternion");
    return;
  }
  if (has_rpy) {
    if (const auto r = read_fixed(s, "rpy", 3, "roll pitch yaw")) {
      out.parent_T_child.rotation = geometry::quaternion_from_rpy((*r)[0], (*r)[1], (*r)[2]);
    }
    return;
  }
  if (const auto q = read_fixed(s, "quaternion", 4, "x y z w")) {
    const Eigen::Quaterniond quat((*q)[3], (*q)[0], (*q)[1], (*q)[2]);
    if (std::abs(quat.norm() - 1.0) > 1e-3) {
      s.value_error("quaternion", "norm must be within 1e-3 of 1, got " + fmt(quat.norm()));
    } else {
      out.parent_T_child.rotation = quat.normalized();
    }
  }
}

void read_static_transforms(const Section& root, RuntimeConfig& cfg) {
  for_each_table(root, "static_transform", kMaxStaticTransforms, [&](const Section& s, bool fits) {
    StaticTransformConfig t;
    read_static_transform(s, t);
    if (fits) cfg.static_transforms[static_cast<std::size_t>(cfg.num_static_transforms++)] = t;
  });
}

void read_sim(const Section& s, SimLcmConfig& sim) {
  s.reject_unknown({"enabled", "seed", "radius", "speed", "imu_rate", "odom_rate", "imu_channel",
                    "odom_channel", "truth_channel", "gyro_noise", "gyro_bias", "accel_noise",
                    "accel_bias", "orientation_noise", "yaw_error", "yaw_error_time", "odom_speed_noise",
                    "odom_yaw_rate_noise", "wheel_slip"});
  s.read("enabled", sim.enabled);
  read_int(s, "seed", sim.seed, 0, std::numeric_limits<std::int64_t>::max());
  read_number(s, "radius", sim.figure_eight_radius_m, positive_finite, "must be > 0 m and finite");
  read_number(s, "speed", sim.speed_mps, positive_finite, "must be > 0 m/s and finite");
  read_number(s, "imu_rate", sim.imu_rate_hz, positive_finite, "must be > 0 Hz and finite");
  read_number(s, "odom_rate", sim.odom_rate_hz, positive_finite, "must be > 0 Hz and finite");
  s.read_name("imu_channel", sim.imu_channel);
  s.read_name("odom_channel", sim.odom_channel);
  s.read_name("truth_channel", sim.truth_channel);
  const std::pair<std::string_view, double*> magnitudes[] = {
      {"gyro_noise", &sim.gyro_noise_rad_s},
      {"gyro_bias", &sim.gyro_bias_rad_s},
      {"accel_noise", &sim.accel_noise_mps2},
      {"accel_bias", &sim.accel_bias_mps2},
      {"orientation_noise", &sim.orientation_noise_rad},
      {"yaw_error", &sim.yaw_error_rad},
      {"odom_speed_noise", &sim.odom_speed_noise_mps},
      {"odom_yaw_rate_noise", &sim.odom_yaw_rate_noise_rad_s}};
  for (const auto& [k, v] : magnitudes) read_number(s, k, *v, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "yaw_error_time", sim.yaw_error_time_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "wheel_slip", sim.wheel_slip, [](double v) { return v >= 0 && v < 1; },
              "must be >= 0 and < 1");
}

void read_root(const Section& root, RuntimeConfig& cfg) {
  // The devices' sections are theirs to name (devices/device_registry.cpp).
  std::vector<std::string_view> sections{"filter",   "realtime",         "lcm", "publish", "sensor",
                                         "instance", "static_transform", "sim"};
  for (std::string_view d : config::device_sections()) sections.push_back(d);
  root.reject_unknown(sections);
  Diagnostics& d = root.diag();
  read_filter(Section(section_table(root, "filter"), "filter", d), cfg);
  read_realtime(Section(section_table(root, "realtime"), "realtime", d), cfg.realtime);
  read_lcm(Section(section_table(root, "lcm"), "lcm", d), cfg);
  std::vector<ChannelUse> publish_channels;
  read_publish(Section(section_table(root, "publish"), "publish", d), cfg.publish, publish_channels);
  std::vector<config::SensorSite> sites;
  read_sensors(root, cfg, publish_channels, 0, sites);
  read_instances(root, cfg, publish_channels, sites);
  // Absent max_rate: what the loop drains per second (2 x queue_size a tick).
  for (int i = 0; i < cfg.num_sensors; ++i) {
    SensorConfig& sc = cfg.sensors[static_cast<std::size_t>(i)];
    if (sc.max_rate_hz == 0.0) sc.max_rate_hz = 2.0 * sc.params.queue_size * cfg.rate_hz;
  }
  read_static_transforms(root, cfg);
  config::read_devices(root, cfg, sites);
  read_sim(Section(section_table(root, "sim"), "sim", d), cfg.sim);
}

ConfigLoadResult unreadable(const std::string& path, int err) {
  ConfigLoadResult r;
  r.errors.push_back(ConfigError{path, 0, 0, "", std::string("cannot read file: ") + std::strerror(err)});
  return r;
}

}  // namespace

ConfigLoadResult load_config_string(std::string_view toml_text, const std::string& source_name) {
  ConfigLoadResult result;
  Diagnostics diag(source_name);
  if (const std::optional<toml::table> root = config::parse(toml_text, source_name, diag)) {
    RuntimeConfig& cfg = result.config.emplace();
    cfg.source = source_name;
    read_root(Section(&*root, "", diag), cfg);
  }
  if (!diag.empty()) result.config.reset();
  result.errors = diag.take();
  return result;
}

bool read_text_file(const std::string& path, std::string* text, int* err) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    *err = errno;
    return false;
  }
  char buf[1 << 14];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text->append(buf, n);
  // A directory opens fine on Linux and fails here with EISDIR.
  *err = std::ferror(f) ? (errno != 0 ? errno : EIO) : 0;
  std::fclose(f);
  return *err == 0;
}

ConfigLoadResult load_config_file(const std::string& path) {
  std::string text;
  int err = 0;
  if (!read_text_file(path, &text, &err)) return unreadable(path, err);
  return load_config_string(text, path);
}

}  // namespace rtfuse
