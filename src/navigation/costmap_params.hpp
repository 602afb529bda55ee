#pragma once
// What the costmap is asked to do: costmap_2d's inflation layer's
// parameters (inflation_radius, cost_scaling_factor, the robot's inscribed
// radius from its footprint) and how the occupancy grid's cells read.
#include <string>

namespace rtfuse::navigation {

// What an unknown cell (-1) of the occupancy grid costs.
enum class UnknownCells {
  kNoInformation,  // 255, costmap_2d's NO_INFORMATION (a planner decides)
  kFree,           // 0: a robot exploring drives into what it has not seen
  kLethal,         // 254: a robot that only drives where it has looked
};

struct CostmapParams {
  double resolution_m = 0.05;       // the occupancy grid's cell size
  double inscribed_radius_m = 0.2;  // the robot's inscribed radius
  double inflation_radius_m = 0.55;
  double cost_scaling_factor = 10.0;  // k in 252 exp(-k (d - inscribed))
  int occupied_from = 65;             // grid values at or above are obstacles (map_server's 0.65)
  UnknownCells unknown = UnknownCells::kNoInformation;
};

// What is wrong with the parameters, or "" when they can be used.
std::string check(const CostmapParams& p);

}  // namespace rtfuse::navigation
