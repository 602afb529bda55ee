#include "runtime/devices/navigator/navigation_config.hpp"

#include <string>

#include "navigation/costmap_params.hpp"
#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

bool speed_like(double v) { return v > 0 && v <= 100.0; }
bool seconds_like(double v) { return v > 0 && v <= 3600.0; }
bool metres_like(double v) { return v >= 0 && v <= 100.0; }

void read_follower(const Section& s, navigation::FollowerParams& f) {
  read_number(s, "max_linear", f.max_linear_mps, speed_like, "must be in (0, 100] m/s");
  read_number(s, "max_angular", f.max_angular_rps, speed_like, "must be in (0, 100] rad/s");
  read_number(s, "max_linear_accel", f.max_linear_accel_mps2, speed_like, "must be in (0, 100] m/s^2");
  read_number(s, "max_linear_decel", f.max_linear_decel_mps2, speed_like, "must be in (0, 100] m/s^2");
  read_number(s, "max_angular_accel", f.max_angular_accel_rps2, speed_like, "must be in (0, 100] rad/s^2");
  read_number(s, "lookahead_time", f.lookahead_time_s, seconds_like, "must be in (0, 3600] s");
  read_number(s, "min_lookahead", f.min_lookahead_m, metres_like, "must be in [0, 100] m");
  read_number(s, "max_lookahead", f.max_lookahead_m, metres_like, "must be in [0, 100] m");
  read_number(s, "goal_tolerance", f.goal_tolerance_m, metres_like, "must be in [0, 100] m");
  read_number(s, "approach_distance", f.approach_distance_m, metres_like, "must be in [0, 100] m");
  read_number(s, "min_approach_speed", f.min_approach_speed_mps, metres_like, "must be in [0, 100] m/s");
  read_number(s, "regulated_min_radius", f.regulated_min_radius_m, metres_like, "must be in [0, 100] m");
  double angle_deg = f.rotate_to_heading_min_angle_rad * 180.0 / 3.14159265358979323846;
  if (read_number(s, "rotate_to_heading_angle_deg", angle_deg, [](double v) { return v > 0 && v <= 180.0; },
                  "must be in (0, 180] degrees")) {
    f.rotate_to_heading_min_angle_rad = angle_deg * 3.14159265358979323846 / 180.0;
  }
  read_number(s, "command_rate", f.command_rate_hz, [](double v) { return v >= 1.0 && v <= 1000.0; },
              "must be between 1 and 1000 Hz");
  read_number(s, "estimate_timeout", f.estimate_timeout_s, seconds_like, "must be in (0, 3600] s");
  read_number(s, "map_timeout", f.map_timeout_s, seconds_like, "must be in (0, 3600] s");
  std::string why;
  if (!f.check(&why)) s.table_error("navigation", why);
}

void read_navigation(const Section& s, NavigationSection& n) {
  s.reject_unknown({"follow", "drop_speckles", "goal_channel", "stop_channel", "path_channel", "cmd_vel_channel", "status_channel",
                    "inscribed_radius", "inflation_radius", "cost_scaling_factor", "unknown", "cost_weight", "smooth_cost",
                    "map_delay", "plan_delay", "off_path", "max_linear", "max_angular", "max_linear_accel",
                    "max_linear_decel", "max_angular_accel", "lookahead_time", "min_lookahead", "max_lookahead",
                    "goal_tolerance", "approach_distance", "min_approach_speed", "regulated_min_radius",
                    "rotate_to_heading_angle_deg", "command_rate", "estimate_timeout", "map_timeout"});
  n.enabled = true;
  s.read("follow", n.follow);
  s.read("drop_speckles", n.drop_speckles);
  s.read_name("goal_channel", n.goal_channel);
  s.read_name("stop_channel", n.stop_channel);
  s.read_name("path_channel", n.path_channel);
  s.read_name("cmd_vel_channel", n.cmd_vel_channel);
  s.read_name("status_channel", n.status_channel);
  read_number(s, "inscribed_radius", n.inscribed_radius_m, metres_like, "must be in [0, 100] m");
  read_number(s, "inflation_radius", n.inflation_radius_m, metres_like, "must be in [0, 100] m");
  read_number(s, "cost_scaling_factor", n.cost_scaling_factor, non_negative_finite, "must be >= 0 and finite");
  std::string unknown = n.unknown_free ? "free" : "blocked";
  if (s.read("unknown", unknown)) {
    if (unknown == "free") {
      n.unknown_free = true;
    } else if (unknown == "blocked") {
      n.unknown_free = false;
    } else {
      s.value_error("unknown", "must be \"free\" (drive into what the camera has not seen) or \"blocked\", got \"" +
                                   unknown + "\"");
    }
  }
  read_number(s, "cost_weight", n.cost_weight, [](double v) { return v >= 0 && v <= 1000.0; },
              "must be between 0 and 1000");
  read_int(s, "smooth_cost", n.smooth_cost, 0, 253);
  read_number(s, "map_delay", n.map_delay_s, [](double v) { return v >= 0 && v <= 10.0; },
              "must be between 0 and 10 s");
  read_number(s, "plan_delay", n.plan_delay_s, [](double v) { return v >= 0 && v <= 10.0; },
              "must be between 0 and 10 s");
  read_number(s, "off_path", n.off_path_m, [](double v) { return v > 0 && v <= 100.0; }, "must be in (0, 100] m");
  read_follower(s, n.follower);
}

}  // namespace

void read_navigation_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* t = section_table(root, "navigation");
  if (!t) return;
  Diagnostics& d = root.diag();
  NavigationSection& n = cfg.hardware.navigation;
  read_navigation(Section(t, "navigation", d), n);
  const MappingSection& m = cfg.hardware.mapping;
  if (!section_table(root, "mapping")) {
    Section(t, "navigation", d).table_error("navigation", "needs a [mapping] section: it plans on the mapper's grid");
    return;
  }
  navigation::CostmapParams p;
  p.resolution_m = m.resolution_m;
  p.inscribed_radius_m = n.inscribed_radius_m;
  p.inflation_radius_m = n.inflation_radius_m;
  p.cost_scaling_factor = n.cost_scaling_factor;
  const std::string bad = navigation::check(p);
  if (!bad.empty()) Section(t, "navigation", d).table_error("navigation", bad);
  if (m.grid_rate_hz <= 0.0) {
    Section(t, "navigation", d).table_error("navigation", "needs mapping.grid_rate > 0: it plans on the grid");
  }
}

}  // namespace rtfuse::config
