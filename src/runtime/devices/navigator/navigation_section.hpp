#pragma once
// [navigation]: goals planned on the mapper's grid and, when `follow` is
// on, followed with velocity commands (navigator_device.hpp). Plain
// values; the navigator turns them into the navigation layer's
// parameters. Schema: docs/configuration.md.
#include "navigation/follower_params.hpp"
#include "runtime/config/name.hpp"

namespace rtfuse {

struct NavigationSection {
  bool enabled = false;
  // The part that moves the robot: off unless asked for. Off, goals are
  // still planned and published, and a goal gets zero commands with the
  // reason "disabled".
  bool follow = false;
  Name goal_channel{"rtfuse/goal"};
  Name stop_channel{"rtfuse/stop"};
  Name path_channel{"rtfuse/path"};
  Name cmd_vel_channel{"rtfuse/cmd_vel"};
  Name status_channel{"rtfuse/nav_status"};
  // The costmap (costmap_2d's inflation layer) on the mapper's grid.
  double inscribed_radius_m = 0.3;
  double inflation_radius_m = 0.8;
  double cost_scaling_factor = 5.0;
  // Unknown cells: "free" (a robot exploring drives into what it has not
  // seen; it starts with an empty map) or "blocked".
  bool unknown_free = true;
  // Lone obstacle cells read as free (navigation/speckle_filter.hpp):
  // stereo's scattered false hits would otherwise each close a disc of
  // the inscribed radius.
  bool drop_speckles = false;
  // The planner: a step's cost is its length times 1 + cost_weight *
  // cost / 252.
  double cost_weight = 2.0;
  // The path followed is the plan smoothed: straight segments over cells
  // whose cost is below smooth_cost (100: about 0.19 m beyond the inscribed
  // radius with the default decay), so a segment keeps its distance from
  // what the map calls an obstacle; 0: the plan's cells as they are.
  // Straight segments matter beyond looks: on a staircase of grid cells the
  // pursuit turns by a few hundredths of a radian a second all the time,
  // which an IMU learning its bias at standstill takes for a bias.
  int smooth_cost = 100;
  // Determinism budgets (docs/design.md, "The navigator"): a grid made from
  // the keyframes up to stamp s is planned on from tick s + map_delay; a
  // plan asked at tick t is followed from tick t + plan_delay.
  double map_delay_s = 1.0;
  double plan_delay_s = 0.2;
  // Farther than this from its path, the robot asks for a new one.
  double off_path_m = 0.5;
  navigation::FollowerParams follower;
};

}  // namespace rtfuse
