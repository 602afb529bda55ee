#pragma once
// The cell costs of a costmap, with costmap_2d's values so a user reads them
// as in ROS: 0 free, 1..252 near an obstacle (inflation), 253 within the
// robot's inscribed radius of one (its centre there means a collision),
// 254 the obstacle itself, 255 unknown. A cost grid is row-major from the
// lowest y, as nav_msgs/OccupancyGrid.
#include <cstddef>
#include <cstdint>

namespace rtfuse::navigation {

inline constexpr std::uint8_t kCostFree = 0;
inline constexpr std::uint8_t kCostInscribed = 253;
inline constexpr std::uint8_t kCostLethal = 254;
inline constexpr std::uint8_t kCostUnknown = 255;
// The largest cost inflation gives beyond the inscribed radius.
inline constexpr std::uint8_t kCostInflatedMax = 252;

// A cost grid as a planner reads it (not owned).
struct CostView {
  const std::uint8_t* cost = nullptr;
  int width = 0;
  int height = 0;

  std::uint8_t at(int x, int y) const noexcept {
    return cost[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
  }
  bool valid() const noexcept { return cost != nullptr && width > 0 && height > 0; }
};

}  // namespace rtfuse::navigation
