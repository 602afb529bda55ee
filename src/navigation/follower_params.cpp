#include "navigation/follower_params.hpp"

#include <cmath>

namespace rtfuse::navigation {

namespace {

// The upper bounds are not physics: they keep every product the follower
// and the gate form (speeds by seconds, seconds by 1e9 ns) finite and in
// range, whatever a config file says.
bool param_in_range(double v, double lo, bool lo_open, double hi) noexcept {
  return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
}

bool param_fail(std::string* error, const char* message) {
  if (error) *error = message;
  return false;
}

}  // namespace

bool FollowerParams::check(std::string* error) const {
  if (!param_in_range(max_linear_mps, 0.0, true, 10.0)) return param_fail(error, "max_linear_mps must be in (0, 10]");
  if (!param_in_range(max_angular_rps, 0.0, true, 20.0)) return param_fail(error, "max_angular_rps must be in (0, 20]");
  if (!param_in_range(max_linear_accel_mps2, 0.0, true, 100.0)) {
    return param_fail(error, "max_linear_accel_mps2 must be in (0, 100]");
  }
  if (!param_in_range(max_linear_decel_mps2, 0.0, true, 100.0)) {
    return param_fail(error, "max_linear_decel_mps2 must be in (0, 100]");
  }
  if (!param_in_range(max_angular_accel_rps2, 0.0, true, 1000.0)) {
    return param_fail(error, "max_angular_accel_rps2 must be in (0, 1000]");
  }
  if (!param_in_range(lookahead_time_s, 0.0, false, 10.0)) return param_fail(error, "lookahead_time_s must be in [0, 10]");
  if (!param_in_range(min_lookahead_m, 0.0, true, 100.0)) return param_fail(error, "min_lookahead_m must be in (0, 100]");
  if (!param_in_range(max_lookahead_m, min_lookahead_m, false, 100.0)) {
    return param_fail(error, "max_lookahead_m must be in [min_lookahead_m, 100]");
  }
  if (!param_in_range(search_window_m, 0.0, true, 1000.0)) return param_fail(error, "search_window_m must be in (0, 1000]");
  if (!param_in_range(goal_tolerance_m, 0.0, true, 10.0)) return param_fail(error, "goal_tolerance_m must be in (0, 10]");
  if (!param_in_range(approach_distance_m, 0.0, false, 100.0)) {
    return param_fail(error, "approach_distance_m must be in [0, 100]");
  }
  // Above zero: a floor of zero would let the robot stall short of the goal.
  if (!param_in_range(min_approach_speed_mps, 0.0, true, max_linear_mps)) {
    return param_fail(error, "min_approach_speed_mps must be in (0, max_linear_mps]");
  }
  if (!param_in_range(regulated_min_radius_m, 0.0, false, 100.0)) {
    return param_fail(error, "regulated_min_radius_m must be in [0, 100]");
  }
  if (!param_in_range(rotate_to_heading_min_angle_rad, 0.0, true, 3.141592653589793)) {
    return param_fail(error, "rotate_to_heading_min_angle_rad must be in (0, pi]");
  }
  if (!param_in_range(command_rate_hz, 1.0, false, 1000.0)) return param_fail(error, "command_rate_hz must be in [1, 1000]");
  if (!param_in_range(estimate_timeout_s, 0.0, true, 3600.0)) {
    return param_fail(error, "estimate_timeout_s must be in (0, 3600]");
  }
  if (!param_in_range(map_timeout_s, 0.0, true, 3600.0)) return param_fail(error, "map_timeout_s must be in (0, 3600]");
  if (!param_in_range(blocked_check_distance_m, 0.0, false, 100.0)) {
    return param_fail(error, "blocked_check_distance_m must be in [0, 100]");
  }
  if (lethal_from < 1 || lethal_from > 255) return param_fail(error, "lethal_from must be in [1, 255]");
  return true;
}

}  // namespace rtfuse::navigation
