#include "sim/drive_scenario.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>

#include "runtime/config/toml_reader.hpp"
#include "sim/camera_world.hpp"
#include "sim/path_plan.hpp"
#include "core/physical_constants.hpp"

namespace rtfuse::sim {

namespace {

using config::Diagnostics;
using config::fmt;
using config::read_fixed;
using config::read_int;
using config::read_number;
using config::Section;

constexpr double kDeg = kPi / 180.0;

auto in_range(double lo, double hi) {
  return [lo, hi](double v) { return v > lo && v <= hi; };
}

// Reads `k` as a string that must be one of `names`; the index, or -1.
int read_choice(const Section& s, std::string_view k, std::initializer_list<std::string_view> names) {
  std::string v;
  if (!s.read(k, v)) return -1;
  int i = 0;
  std::string all;
  for (std::string_view n : names) {
    if (v == n) return i;
    all += (i++ == 0 ? "" : ", ") + config::in_quotes(n);
  }
  s.value_error(k, "must be one of " + all + ", got " + config::in_quotes(v));
  return -1;
}

// Exactly one of two alternative keys; returns which (0 or 1), -1 if neither
// or both (with an error).
int one_of(const Section& s, std::string_view a, std::string_view b) {
  const bool ha = s.has(a);
  const bool hb = s.has(b);
  if (ha && hb) {
    s.key_error(b, "give either " + config::in_quotes(a) + " or " + config::in_quotes(b) + ", not both");
    return -1;
  }
  if (!ha && !hb) {
    s.table_error(s.key(a), "missing: give " + config::in_quotes(a) + " or " + config::in_quotes(b));
    return -1;
  }
  return ha ? 0 : 1;
}

// --- [[path]] ---------------------------------------------------------------

constexpr double kMaxSpeed = 20.0;
constexpr double kMaxLength = 100'000.0;
constexpr double kMaxTurnDeg = 36'000.0;
constexpr double kMaxYawRateDps = 720.0;

void read_speed(const Section& s, PathSegment& g) {
  s.require({"speed_mps"});
  read_number(s, "speed_mps", g.speed_mps, in_range(0.0, kMaxSpeed), "must be > 0 and <= 20 m/s");
}

void read_angle(const Section& s, PathSegment& g) {
  s.require({"angle_deg"});
  double deg = 0.0;
  if (read_number(s, "angle_deg", deg, [](double v) { return v != 0.0 && std::abs(v) <= kMaxTurnDeg; },
                  "must be non-zero (positive turns left) and within +-36000 deg")) {
    g.angle_rad = deg * kDeg;
  }
}

void read_segment(const Section& s, PathSegment& g) {
  const int type = read_choice(s, "type", {"straight", "arc", "spin", "figure_eight", "stop"});
  s.require({"type"});
  switch (type) {
    case 0: {
      s.reject_unknown({"type", "length_m", "duration_s", "speed_mps"});
      g.type = SegmentType::kStraight;
      read_speed(s, g);
      const int which = one_of(s, "length_m", "duration_s");
      if (which == 0) {
        read_number(s, "length_m", g.length_m, in_range(0.0, kMaxLength), "must be > 0 and <= 100000 m");
      } else if (which == 1) {
        double d = 0.0;
        // At cruise speed; the ramps at the ends make the drive take longer.
        if (read_number(s, "duration_s", d, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s")) {
          g.length_m = d * g.speed_mps;
        }
      }
      break;
    }
    case 1: {
      s.reject_unknown({"type", "radius_m", "yaw_rate_dps", "angle_deg", "speed_mps"});
      g.type = SegmentType::kArc;
      read_speed(s, g);
      read_angle(s, g);
      const int which = one_of(s, "radius_m", "yaw_rate_dps");
      if (which == 0) {
        read_number(s, "radius_m", g.radius_m, in_range(0.01, 10'000.0), "must be > 0.01 and <= 10000 m");
      } else if (which == 1) {
        double rate = 0.0;
        if (read_number(s, "yaw_rate_dps", rate, in_range(0.0, kMaxYawRateDps),
                        "must be > 0 and <= 720 deg/s (the sign of angle_deg gives the direction)") &&
            g.speed_mps > 0.0) {
          g.radius_m = g.speed_mps / (rate * kDeg);
        }
      }
      break;
    }
    case 2:
      s.reject_unknown({"type", "angle_deg", "yaw_rate_dps"});
      g.type = SegmentType::kSpin;
      read_angle(s, g);
      s.require({"yaw_rate_dps"});
      if (double rate = 0.0; read_number(s, "yaw_rate_dps", rate, in_range(0.0, kMaxYawRateDps),
                                         "must be > 0 and <= 720 deg/s (the sign of angle_deg gives the direction)")) {
        g.yaw_rate_rad_s = rate * kDeg;
      }
      break;
    case 3: {
      s.reject_unknown({"type", "radius_m", "laps", "speed_mps", "first_turn"});
      g.type = SegmentType::kFigureEight;
      read_speed(s, g);
      s.require({"radius_m", "laps"});
      read_number(s, "radius_m", g.radius_m, in_range(0.05, 10'000.0), "must be > 0.05 and <= 10000 m");
      read_int(s, "laps", g.laps, 1, 10'000);
      g.right_first = read_choice(s, "first_turn", {"left", "right"}) == 1;
      break;
    }
    case 4:
      s.reject_unknown({"type", "duration_s"});
      g.type = SegmentType::kStop;
      s.require({"duration_s"});
      read_number(s, "duration_s", g.duration_s, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s");
      break;
    default: break;  // bad or missing type: already reported
  }
}

// --- [robot] ---------------------------------------------------------------

// A list of CANopen node ids, `count` long.
void read_nodes(const Section& s, std::string_view k, int count, std::uint8_t* out) {
  const toml::array* a = s.array(k);
  if (a == nullptr) return;
  if (static_cast<int>(a->size()) != count) {
    s.key_error(k, "expected " + std::to_string(count) + (count == 1 ? " node id" : " node ids (front, rear)") +
                       " for this kinematics, got " + std::to_string(a->size()));
    return;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& e = *a->get(i);
    const std::string element = s.key(k) + "[" + std::to_string(i) + "]";
    const auto* v = e.as_integer();
    if (v == nullptr) {
      s.diag().add(e.source(), element, "expected integer, got " + config::type_name(e.type()));
    } else if (v->get() < 1 || v->get() > 127) {
      s.diag().add(e.source(), element, "a CANopen node id is 1..127, got " + std::to_string(v->get()));
    } else {
      out[i] = static_cast<std::uint8_t>(v->get());
    }
  }
}

void read_radius_errors(const Section& s, std::string_view k, int count, double* out) {
  const auto values = config::read_numbers(s, k);
  if (!values) return;
  if (static_cast<int>(values->size()) != count) {
    s.key_error(k, "expected " + std::to_string(count) + " fractions (one per wheel of the side), got " +
                       std::to_string(values->size()));
    return;
  }
  for (int i = 0; i < count; ++i) {
    const double v = (*values)[static_cast<std::size_t>(i)];
    if (!(v > -0.5 && v < 0.5)) {
      s.value_error(k, "a radius error is a fraction of the radius, between -0.5 and 0.5, got " + fmt(v));
      return;
    }
    out[i] = v;
  }
}

void read_robot(const Section& s, RobotBody& r) {
  s.reject_unknown({"kinematics", "track_width_m", "wheel_radius_m", "counts_per_rev", "gear_ratio", "encoder_bits",
                    "encoder_signed", "heartbeat_period_s", "left_nodes", "right_nodes", "left_radius_error",
                    "right_radius_error", "invert_left", "invert_right"});
  if (read_choice(s, "kinematics", {"differential", "skid_steer"}) == 1) r.kinematics = DriveKinematics::kSkidSteer;
  read_number(s, "track_width_m", r.track_width_m, in_range(0.0, 10.0), "must be > 0 and <= 10 m");
  read_number(s, "wheel_radius_m", r.wheel_radius_m, in_range(0.0, 5.0), "must be > 0 and <= 5 m");
  std::int64_t cpr = 0;
  if (s.read("counts_per_rev", cpr)) {
    if (cpr < 1 || cpr > (std::int64_t{1} << 30)) {
      s.value_error("counts_per_rev", "must be between 1 and 2^30, got " + std::to_string(cpr));
    } else {
      r.counts_per_rev = static_cast<double>(cpr);
    }
  }
  read_number(s, "gear_ratio", r.gear_ratio, in_range(0.0, 1000.0), "must be > 0 and <= 1000");
  read_int(s, "encoder_bits", r.encoder_bits, 8, 32);
  s.read("encoder_signed", r.encoder_signed);
  s.read("invert_left", r.invert_left);
  s.read("invert_right", r.invert_right);
  double hb = 0.1;
  if (read_number(s, "heartbeat_period_s", hb, [](double v) { return v >= 0.0 && v <= 60.0; },
                  "must be between 0 (no heartbeat) and 60 s")) {
    r.heartbeat_period_ns = sec_to_ns(hb);
  }

  const int per_side = r.kinematics == DriveKinematics::kSkidSteer ? 2 : 1;
  r.wheel_count = 2 * per_side;
  std::uint8_t left[2] = {1, 3};
  std::uint8_t right[2] = {2, 4};
  double left_error[2] = {0.0, 0.0};
  double right_error[2] = {0.0, 0.0};
  s.require({"left_nodes", "right_nodes"});
  read_nodes(s, "left_nodes", per_side, left);
  read_nodes(s, "right_nodes", per_side, right);
  read_radius_errors(s, "left_radius_error", per_side, left_error);
  read_radius_errors(s, "right_radius_error", per_side, right_error);
  for (int i = 0; i < per_side; ++i) {
    r.wheels[static_cast<std::size_t>(i)] = SimWheel{left[i], true, left_error[i]};
    r.wheels[static_cast<std::size_t>(per_side + i)] = SimWheel{right[i], false, right_error[i]};
  }
  for (int i = 0; i < r.wheel_count; ++i) {
    for (int j = 0; j < i; ++j) {
      const SimWheel& w = r.wheels[static_cast<std::size_t>(i)];
      if (w.node_id == r.wheels[static_cast<std::size_t>(j)].node_id) {
        s.key_error(w.left ? "left_nodes" : "right_nodes",
                    "node id " + std::to_string(w.node_id) + " is used twice; every encoder needs its own");
      }
    }
  }
}

// --- [slip], [[dropout]] ----------------------------------------------------

// Wheel names for slip episodes, as a mask over RobotBody::wheels.
std::uint8_t wheel_mask(const Section& s, std::string_view k, const RobotBody& r) {
  std::string name;
  if (!s.read(k, name)) return 0;
  const bool skid = r.kinematics == DriveKinematics::kSkidSteer;
  if (name == "all") return skid ? 0x0F : 0x03;
  if (name == "left") return skid ? 0x03 : 0x01;
  if (name == "right") return skid ? 0x0C : 0x02;
  if (skid) {
    if (name == "left_front") return 0x01;
    if (name == "left_rear") return 0x02;
    if (name == "right_front") return 0x04;
    if (name == "right_rear") return 0x08;
  }
  s.value_error(k, std::string("must be ") +
                       (skid ? "'left', 'right', 'all', 'left_front', 'left_rear', 'right_front' or 'right_rear'"
                             : "'left', 'right' or 'all' (a differential drive has one wheel per side)") +
                       ", got " + config::in_quotes(name));
  return 0;
}

void read_slip(const Section& root, WheelSlip& slip, const RobotBody& robot) {
  const Section s(config::section_table(root, "slip"), "slip", root.diag());
  s.reject_unknown({"noise_fraction", "correlation_time_s", "episode"});
  read_number(s, "noise_fraction", slip.noise_fraction, [](double v) { return v >= 0.0 && v < 0.5; },
              "must be >= 0 and < 0.5 (a 1-sigma fraction of the distance rolled)");
  read_number(s, "correlation_time_s", slip.correlation_time_s, in_range(0.001, 3600.0),
              "must be > 0.001 and <= 3600 s");
  config::for_each_table(s, "episode", kMaxSlipEpisodes, [&](const Section& e, bool fits) {
    e.reject_unknown({"start_s", "duration_s", "wheel", "fraction"});
    e.require({"start_s", "duration_s", "wheel", "fraction"});
    SlipEpisode ep;
    read_number(e, "start_s", ep.start_s, [](double v) { return v >= 0.0 && v <= 86400.0; },
                "must be >= 0 and <= 86400 s");
    read_number(e, "duration_s", ep.duration_s, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s");
    ep.wheel_mask = wheel_mask(e, "wheel", robot);
    read_number(e, "fraction", ep.fraction, [](double v) { return v > -1.0 && v <= 10.0 && v != 0.0; },
                "must be non-zero, > -1 (the wheel would turn backwards) and <= 10");
    if (fits) slip.episodes[static_cast<std::size_t>(slip.episode_count++)] = ep;
  });
}

void read_dropouts(const Section& root, DriveScenario& sc) {
  config::for_each_table(root, "dropout", kMaxDropouts, [&](const Section& s, bool fits) {
    s.reject_unknown({"node", "start_s", "duration_s"});
    s.require({"node", "start_s", "duration_s"});
    EncoderDropout d;
    read_int(s, "node", d.node_id, 1, 127);
    read_number(s, "start_s", d.start_s, [](double v) { return v >= 0.0 && v <= 86400.0; },
                "must be >= 0 and <= 86400 s");
    read_number(s, "duration_s", d.duration_s, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s");
    if (s.has("node") && d.node_id != 0) {
      bool known = false;
      for (int i = 0; i < sc.robot.wheel_count; ++i) {
        known = known || sc.robot.wheels[static_cast<std::size_t>(i)].node_id == d.node_id;
      }
      if (!known) s.value_error("node", "no wheel of [robot] has node id " + std::to_string(d.node_id));
    }
    for (int i = 0; i < sc.dropout_count; ++i) {
      const EncoderDropout& o = sc.dropouts[static_cast<std::size_t>(i)];
      if (o.node_id == d.node_id && d.start_s < o.start_s + o.duration_s && o.start_s < d.start_s + d.duration_s) {
        s.key_error("start_s", "overlaps an earlier dropout of node " + std::to_string(d.node_id) +
                                   "; merge them into one");
      }
    }
    if (fits) sc.dropouts[static_cast<std::size_t>(sc.dropout_count++)] = d;
  });
}

// --- [[obstacle]] --------------------------------------------------------------

void read_obstacles(const Section& root, DriveScenario& sc, std::vector<toml::source_region>& where) {
  const CameraWorldConfig world;  // the free area obstacles stand in
  config::for_each_table(root, "obstacle", CameraWorldConfig::kMaxObstacles, [&](const Section& s, bool fits) {
    s.reject_unknown({"x_m", "y_m", "size_x_m", "size_y_m", "height_m"});
    s.require({"x_m", "y_m", "size_x_m", "size_y_m"});
    ObstacleBox o;
    const auto coordinate = [](double v) { return v >= -1000.0 && v <= 1000.0; };
    read_number(s, "x_m", o.x, coordinate, "must be within -1000..1000 m");
    read_number(s, "y_m", o.y, coordinate, "must be within -1000..1000 m");
    read_number(s, "size_x_m", o.size_x, in_range(0.0, 20.0), "must be > 0 and <= 20 m");
    read_number(s, "size_y_m", o.size_y, in_range(0.0, 20.0), "must be > 0 and <= 20 m");
    read_number(s, "height_m", o.height, in_range(0.0, 5.0), "must be > 0 and <= 5 m");
    if (o.x - 0.5 * o.size_x < world.min_x || o.x + 0.5 * o.size_x > world.max_x ||
        o.y - 0.5 * o.size_y < world.min_y || o.y + 0.5 * o.size_y > world.max_y) {
      s.key_error("x_m", "the obstacle must stand inside the drive area, x " + fmt(world.min_x) + ".." +
                             fmt(world.max_x) + " m, y " + fmt(world.min_y) + ".." + fmt(world.max_y) + " m");
    }
    where.push_back(s.key_where("x_m"));
    if (fits) sc.obstacles.push_back(o);
  });
}

// The path keeps half the track and 10 cm from every obstacle: a scripted
// drive through a wall would make the camera see the inside of a box.
void check_clearance(const DriveScenario& sc, const PathPlan& plan, const std::vector<toml::source_region>& where,
                     Diagnostics& diag) {
  const double need = 0.5 * sc.robot.track_width_m + 0.1;
  for (std::size_t i = 0; i < sc.obstacles.size(); ++i) {
    const ObstacleBox& o = sc.obstacles[i];
    for (double t = 0.0; t <= plan.end_time() + 0.02; t += 0.02) {
      const PathPoint p = plan.at(t);
      const double dx = std::max(std::abs(p.x - o.x) - 0.5 * o.size_x, 0.0);
      const double dy = std::max(std::abs(p.y - o.y) - 0.5 * o.size_y, 0.0);
      if (dx * dx + dy * dy < need * need) {
        diag.add(where[i], "obstacle[" + std::to_string(i) + "]",
                 "the path passes " + fmt(std::sqrt(dx * dx + dy * dy)) + " m from this obstacle at t = " +
                     fmt(std::floor(t * 10.0) / 10.0) + " s (x " + fmt(p.x) + ", y " + fmt(p.y) +
                     "); the robot needs " + fmt(need) + " m (half its track and 0.1 m)");
        break;
      }
    }
  }
}

// --- [drive], [base], [[goal]] ---------------------------------------------------

void read_base(const Section& s, BaseLimits& b) {
  s.reject_unknown({"max_wheel_speed_mps", "max_wheel_accel_mps2", "command_latency_s", "command_timeout_s"});
  read_number(s, "max_wheel_speed_mps", b.max_wheel_speed_mps, in_range(0.0, 10.0), "must be > 0 and <= 10 m/s");
  read_number(s, "max_wheel_accel_mps2", b.max_wheel_accel_mps2, in_range(0.0, 50.0),
              "must be > 0 and <= 50 m/s^2");
  read_number(s, "command_latency_s", b.command_latency_s, in_range(0.0, 1.0),
              "must be > 0 and <= 1 s (a command acts after it arrives, never at the instant it is issued)");
  read_number(s, "command_timeout_s", b.command_timeout_s, in_range(0.0, 60.0), "must be > 0 and <= 60 s");
}

// The distance from (x, y) to a box's footprint; 0 inside it.
double obstacle_gap(const ObstacleBox& o, double x, double y) noexcept {
  const double dx = std::max(std::abs(x - o.x) - 0.5 * o.size_x, 0.0);
  const double dy = std::max(std::abs(y - o.y) - 0.5 * o.size_y, 0.0);
  return std::sqrt(dx * dx + dy * dy);
}

// Where the robot must be able to stand: the path's clearance rule.
double standing_clearance(const RobotBody& robot) noexcept { return 0.5 * robot.track_width_m + 0.1; }

// Goals are read after the robot and the obstacles: a goal the robot
// cannot stand at would only show as a navigator that never arrives.
void read_goals(const Section& root, DriveScenario& sc, std::vector<toml::source_region>& where) {
  const CameraWorldConfig world;
  const double need = standing_clearance(sc.robot);
  config::for_each_table(root, "goal", kMaxDriveGoals, [&](const Section& s, bool fits) {
    s.reject_unknown({"x_m", "y_m", "yaw_deg", "tolerance_m"});
    s.require({"x_m", "y_m"});
    DriveGoal g;
    const bool x = read_number(s, "x_m", g.x_m, [&](double v) { return v >= world.min_x && v <= world.max_x; },
                               "must be within the drive area's x " + fmt(world.min_x) + ".." + fmt(world.max_x) +
                                   " m");
    const bool y = read_number(s, "y_m", g.y_m, [&](double v) { return v >= world.min_y && v <= world.max_y; },
                               "must be within the drive area's y " + fmt(world.min_y) + ".." + fmt(world.max_y) +
                                   " m");
    double yaw = 0.0;
    if (read_number(s, "yaw_deg", yaw, [](double v) { return v >= -360.0 && v <= 360.0; },
                    "must be within -360..360 deg")) {
      g.has_yaw = true;
      g.yaw_rad = yaw * kDeg;
    }
    read_number(s, "tolerance_m", g.tolerance_m, in_range(0.0, 10.0), "must be > 0 and <= 10 m");
    where.push_back(s.key_where("x_m"));
    g.line = static_cast<int>(where.back().begin.line);
    if (x && y) {
      for (std::size_t i = 0; i < sc.obstacles.size(); ++i) {
        const double d = obstacle_gap(sc.obstacles[i], g.x_m, g.y_m);
        if (d <= 0.0) {
          s.key_error("x_m", "the goal is inside obstacle[" + std::to_string(i) + "]");
        } else if (d < need) {
          s.key_error("x_m", "the goal is " + fmt(d) + " m from obstacle[" + std::to_string(i) +
                                 "]; the robot needs " + fmt(need) + " m to stand there (half its track and 0.1 m)");
        }
      }
    }
    if (fits) sc.goals.push_back(g);
  });
}

// --- [imu] --------------------------------------------------------------------

void read_triple(const Section& s, std::string_view k, double scale, std::array<double, 3>& out) {
  if (const auto v = read_fixed(s, k, 3, "x y z")) {
    for (std::size_t i = 0; i < 3; ++i) out[i] = (*v)[i] * scale;
  }
}

void read_imu(const Section& s, SimImuConfig& imu) {
  s.reject_unknown({"model", "address", "rate_hz", "gyro_range_dps", "accel_range_g", "gyro_noise_density_dps_rthz",
                    "accel_noise_density_ug_rthz", "gyro_bias_dps", "accel_bias_mps2", "xyz_m", "rpy_deg",
                    "temperature_c", "vibration_accel_mps2", "vibration_gyro_dps", "vibration_speed_mps"});
  switch (read_choice(s, "model", {"mpu6050", "mpu6500", "mpu9250"})) {
    case 1: imu.model = MpuChip::kMpu6500; break;
    case 2: imu.model = MpuChip::kMpu9250; break;
    default: break;
  }
  read_int(s, "address", imu.address, 0x08, 0x77);
  read_number(s, "rate_hz", imu.rate_hz, in_range(0.0, 8000.0), "must be > 0 and <= 8000 Hz");
  std::int64_t range = 0;
  if (s.read("gyro_range_dps", range)) {
    if (range == 250 || range == 500 || range == 1000 || range == 2000) {
      imu.gyro_range_dps = static_cast<int>(range);
    } else {
      s.value_error("gyro_range_dps", "must be 250, 500, 1000 or 2000, got " + std::to_string(range));
    }
  }
  if (s.read("accel_range_g", range)) {
    if (range == 2 || range == 4 || range == 8 || range == 16) {
      imu.accel_range_g = static_cast<int>(range);
    } else {
      s.value_error("accel_range_g", "must be 2, 4, 8 or 16, got " + std::to_string(range));
    }
  }
  double density = 0.0;
  if (read_number(s, "gyro_noise_density_dps_rthz", density, [](double v) { return v >= 0.0 && v <= 1.0; },
                  "must be >= 0 and <= 1 deg/s/sqrt(Hz) (MPU-6050: 0.005)")) {
    imu.gyro_noise_density = density * kDeg;
  }
  if (read_number(s, "accel_noise_density_ug_rthz", density, [](double v) { return v >= 0.0 && v <= 100'000.0; },
                  "must be >= 0 and <= 100000 ug/sqrt(Hz) (MPU-6050: 400)")) {
    imu.accel_noise_density = density * 1e-6 * kStandardGravity;
  }
  read_triple(s, "gyro_bias_dps", kDeg, imu.gyro_bias_rad_s);
  read_triple(s, "accel_bias_mps2", 1.0, imu.accel_bias_mps2);
  read_triple(s, "xyz_m", 1.0, imu.xyz_m);
  if (const auto v = read_fixed(s, "rpy_deg", 3, "roll pitch yaw")) {
    for (std::size_t i = 0; i < 3; ++i) imu.rpy_rad[i] = (*v)[i] * kDeg;
  }
  read_number(s, "temperature_c", imu.temperature_c, [](double v) { return v >= -40.0 && v <= 85.0; },
              "must be within the chip's -40..85 C");
  read_number(s, "vibration_accel_mps2", imu.vibration_accel_mps2, [](double v) { return v >= 0.0 && v <= 20.0; },
              "must be 0..20 m/s^2 (a Jackal driving: about 0.3)");
  double dps = 0.0;
  if (read_number(s, "vibration_gyro_dps", dps, [](double v) { return v >= 0.0 && v <= 100.0; },
                  "must be 0..100 deg/s (a Jackal driving: about 1)")) {
    imu.vibration_gyro_rad_s = dps * kDeg;
  }
  read_number(s, "vibration_speed_mps", imu.vibration_speed_mps, in_range(0.0, 10.0),
              "must be > 0 and <= 10 m/s");
}

void read_gnss(const Section& s, SimGnssConfig& g) {
  s.reject_unknown({"rate_hz", "latitude_deg", "longitude_deg", "altitude_m", "latency_s", "bias_sigma_m",
                    "vertical_bias_sigma_m", "bias_time_s", "noise_m", "vertical_noise_m", "multipath_per_hour",
                    "multipath_m", "multipath_epochs", "satellites", "antenna_xyz_m", "outage"});
  g.enabled = true;
  read_number(s, "rate_hz", g.rate_hz, in_range(0.0, 20.0), "must be > 0 and <= 20 Hz");
  read_number(s, "latitude_deg", g.latitude_deg, [](double v) { return v >= -84.0 && v <= 84.0; },
              "must be within -84..84 degrees");
  read_number(s, "longitude_deg", g.longitude_deg, [](double v) { return v >= -180.0 && v <= 180.0; },
              "must be within -180..180 degrees");
  read_number(s, "altitude_m", g.altitude_m, [](double v) { return v >= -500.0 && v <= 9000.0; },
              "must be within -500..9000 m");
  read_number(s, "latency_s", g.latency_s, [](double v) { return v >= 0.0 && v <= 1.0; }, "must be 0..1 s");
  const auto metres = [](double v) { return v >= 0.0 && v <= 100.0; };
  read_number(s, "bias_sigma_m", g.bias_sigma_m, metres, "must be 0..100 m");
  read_number(s, "vertical_bias_sigma_m", g.vertical_bias_sigma_m, metres, "must be 0..100 m");
  read_number(s, "bias_time_s", g.bias_time_s, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s");
  read_number(s, "noise_m", g.noise_m, metres, "must be 0..100 m");
  read_number(s, "vertical_noise_m", g.vertical_noise_m, metres, "must be 0..100 m");
  read_number(s, "multipath_per_hour", g.multipath_per_hour, [](double v) { return v >= 0.0 && v <= 3600.0; },
              "must be 0..3600");
  read_number(s, "multipath_m", g.multipath_m, metres, "must be 0..100 m");
  read_int(s, "multipath_epochs", g.multipath_epochs, 1, 100);
  read_int(s, "satellites", g.satellites, 0, 64);
  read_triple(s, "antenna_xyz_m", 1.0, g.antenna_xyz_m);
  config::for_each_table(s, "outage", kMaxGnssOutages, [&](const Section& e, bool fits) {
    e.reject_unknown({"start_s", "duration_s"});
    e.require({"start_s", "duration_s"});
    GnssOutage o;
    read_number(e, "start_s", o.start_s, [](double v) { return v >= 0.0 && v <= 86400.0; },
                "must be >= 0 and <= 86400 s");
    read_number(e, "duration_s", o.duration_s, in_range(0.0, 86400.0), "must be > 0 and <= 86400 s");
    if (fits) g.outages[static_cast<std::size_t>(g.outage_count++)] = o;
  });
}

// --- root -------------------------------------------------------------------

// Where the entries are in the file, for the checks after reading.
struct EntryPlaces {
  std::vector<toml::source_region> path, obstacle, goal;
};

void read_root(const Section& root, DriveScenario& sc, EntryPlaces& where) {
  root.reject_unknown({"duration_s", "seed", "drive", "base", "goal", "limits", "path", "robot", "slip", "dropout",
                       "imu", "gnss", "obstacle"});
  Diagnostics& d = root.diag();
  const Section drive(config::section_table(root, "drive"), "drive", d);
  drive.reject_unknown({"mode"});
  if (read_choice(drive, "mode", {"path", "commanded"}) == 1) sc.mode = DriveMode::kCommanded;
  read_number(root, "duration_s", sc.duration_s, in_range(0.0, 86400.0),
              "must be > 0 and <= 86400 s (leave it out to run as long as the path takes)");
  std::int64_t seed = 1;
  read_int(root, "seed", seed, 0, std::numeric_limits<std::int64_t>::max());
  sc.seed = static_cast<std::uint64_t>(seed);

  const Section limits(config::section_table(root, "limits"), "limits", d);
  limits.reject_unknown({"max_accel_mps2", "max_yaw_accel_dps2"});
  read_number(limits, "max_accel_mps2", sc.limits.max_accel_mps2, in_range(0.0, 20.0), "must be > 0 and <= 20 m/s^2");
  double yaw_accel = 0.0;
  if (read_number(limits, "max_yaw_accel_dps2", yaw_accel, in_range(0.0, 3600.0), "must be > 0 and <= 3600 deg/s^2")) {
    sc.limits.max_yaw_accel_rad_s2 = yaw_accel * kDeg;
  }

  config::for_each_table(root, "path", std::numeric_limits<int>::max(), [&](const Section& s, bool) {
    PathSegment g;
    read_segment(s, g);
    where.path.push_back(s.key_where("type"));
    g.line = static_cast<int>(where.path.back().begin.line);
    g.column = static_cast<int>(where.path.back().begin.column);
    sc.path.push_back(g);
  });

  read_robot(Section(config::section_table(root, "robot"), "robot", d), sc.robot);
  read_slip(root, sc.slip, sc.robot);
  read_dropouts(root, sc);
  read_imu(Section(config::section_table(root, "imu"), "imu", d), sc.imu);
  if (const toml::table* gnss = config::section_table(root, "gnss")) read_gnss(Section(gnss, "gnss", d), sc.gnss);
  read_obstacles(root, sc, where.obstacle);
  read_base(Section(config::section_table(root, "base"), "base", d), sc.base);
  read_goals(root, sc, where.goal);

  if (sc.mode == DriveMode::kCommanded) {
    if (!where.path.empty()) {
      d.add(where.path.front(), "path",
            "a commanded drive ([drive] mode = 'commanded') follows velocity commands, not a scripted path: "
            "remove the [[path]] entries, or set mode = 'path'");
    }
    if (!root.has("duration_s")) {
      d.add(drive.value_where("mode"), "duration_s",
            "missing: a commanded drive needs a duration_s (there is no path to take the length from)");
    }
    // The drive starts at the origin, facing +x: the robot must fit there.
    const double need = standing_clearance(sc.robot);
    for (std::size_t i = 0; i < sc.obstacles.size(); ++i) {
      const double gap = obstacle_gap(sc.obstacles[i], 0.0, 0.0);
      if (gap < need) {
        d.add(where.obstacle[i], "obstacle[" + std::to_string(i) + "]",
              "the robot starts at the origin, " + fmt(gap) + " m from this obstacle; it needs " + fmt(need) +
                  " m (half its track and 0.1 m)");
      }
    }
  } else {
    if (root.has("base")) {
      root.key_error("base", "only a commanded drive has a [base]: set [drive] mode = 'commanded'");
    }
    if (!where.goal.empty()) {
      d.add(where.goal.front(), "goal",
            "goals are for the navigator of a commanded drive: set [drive] mode = 'commanded'");
    }
  }
}

}  // namespace

const char* to_string(SegmentType type) noexcept {
  switch (type) {
    case SegmentType::kStraight: return "straight";
    case SegmentType::kArc: return "arc";
    case SegmentType::kSpin: return "spin";
    case SegmentType::kFigureEight: return "figure_eight";
    case SegmentType::kStop: return "stop";
  }
  return "?";
}

bool load_drive_scenario_string(std::string_view toml_text, const std::string& source_name, DriveScenario* out,
                                std::string* error) {
  Diagnostics diag(source_name);
  DriveScenario sc;
  sc.source = source_name;
  if (const std::optional<toml::table> root = config::parse(toml_text, source_name, diag)) {
    const Section top(&*root, "", diag);
    EntryPlaces where;
    read_root(top, sc, where);
    if (diag.empty() && sc.mode == DriveMode::kPath) {
      // The drive itself: can every segment be driven within the limits, and
      // do the run's timed events fall inside it?
      PathPlan plan;
      PlanProblem problem;
      if (!PathPlan::build(sc, &plan, &problem)) {
        if (problem.segment >= 0) {
          diag.add(where.path[static_cast<std::size_t>(problem.segment)],
                   "path[" + std::to_string(problem.segment) + "]", problem.message);
        } else {
          top.table_error("path", problem.message);
        }
      } else {
        if (sc.duration_s > 0.0 && sc.duration_s < plan.end_time()) {
          top.value_error("duration_s", "the path takes " + fmt(std::ceil(plan.end_time() * 10.0) / 10.0) +
                                            " s with these speeds and limits; make duration_s at least that, "
                                            "or leave it out");
        }
        if (sc.duration_s <= 0.0 && plan.end_time() <= 0.0) {
          top.table_error("duration_s", "the path is empty: give a duration_s for the robot to stand still");
        }
        check_clearance(sc, plan, where.obstacle, diag);
      }
    }
  }
  if (!diag.empty()) {
    if (error != nullptr) {
      error->clear();
      for (const ConfigError& e : diag.take()) *error += (error->empty() ? "" : "\n") + e.to_string();
    }
    return false;
  }
  if (out != nullptr) *out = std::move(sc);
  if (error != nullptr) error->clear();
  return true;
}

bool load_drive_scenario(const std::string& path, DriveScenario* out, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  int err = f == nullptr ? errno : 0;
  std::string text;
  if (f != nullptr) {
    char buf[1 << 14];
    std::size_t n = 0;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
    // A directory opens fine on Linux and fails here with EISDIR.
    if (std::ferror(f)) err = errno != 0 ? errno : EIO;
    std::fclose(f);
  }
  if (err != 0) {
    if (error != nullptr) *error = path + ": cannot read the scenario: " + std::strerror(err);
    return false;
  }
  return load_drive_scenario_string(text, path, out, error);
}

}  // namespace rtfuse::sim
