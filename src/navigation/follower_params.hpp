#pragma once
// What the path follower and its command gate are asked to do. The names
// are the config file's keys; the defaults suit a small indoor base (about
// 0.5 m across, a few tenths of a metre per second), with Nav2's regulated
// pure pursuit's meaning where Nav2 has the same parameter.
#include <string>

namespace rtfuse::navigation {

struct FollowerParams {
  // Limits of every command the gate lets out. There is no reverse limit:
  // the base has no sensor looking backwards, so the follower never
  // commands a negative linear speed (it turns in place instead).
  double max_linear_mps = 0.5;
  double max_angular_rps = 1.0;
  // Between two commands. The linear deceleration is for slowing while
  // driving; a stop is not slowed, it is zero at once.
  double max_linear_accel_mps2 = 0.5;
  double max_linear_decel_mps2 = 1.0;
  double max_angular_accel_rps2 = 2.0;

  // Lookahead distance: speed * lookahead_time_s, within
  // [min_lookahead_m, max_lookahead_m].
  double lookahead_time_s = 1.0;
  double min_lookahead_m = 0.3;
  double max_lookahead_m = 0.9;
  // How far along the path, from the last nearest point, the next one is
  // looked for (progress never goes back).
  double search_window_m = 2.0;

  // Reached within this of the path's last point; then zero.
  double goal_tolerance_m = 0.15;
  // Within this distance left along the path the speed falls in proportion
  // to it, not below min_approach_speed_mps (0: no slowing).
  double approach_distance_m = 0.6;
  double min_approach_speed_mps = 0.05;
  // Where the pursuit's turning radius is below this, the speed is scaled
  // by radius / regulated_min_radius_m (0: no scaling).
  double regulated_min_radius_m = 0.9;
  // When the lookahead point is more than this off the heading, turn in
  // place toward it instead of driving.
  double rotate_to_heading_min_angle_rad = 0.785;

  // The gate: its nominal period, and how old an estimate or a costmap may
  // be before the robot stops.
  double command_rate_hz = 20.0;
  double estimate_timeout_s = 0.5;
  double map_timeout_s = 5.0;
  // The path ahead that must be clear of costs at or above lethal_from
  // (253: the inscribed zone, the robot's centre there touches an
  // obstacle; unknown, 255, always counts).
  double blocked_check_distance_m = 1.0;
  int lethal_from = 253;

  // Whether every value is usable. When not, names the first bad key in
  // *error ("max_linear_mps must be in (0, 10]") when error is not null.
  bool check(std::string* error) const;
};

}  // namespace rtfuse::navigation
