#pragma once
// A cell of a cost grid: column x, row y, row 0 the lowest y
// (nav_msgs/OccupancyGrid's indexing, as cost_values.hpp's CostView).
namespace rtfuse::navigation {

struct GridCell {
  int x = 0;
  int y = 0;
};

inline bool operator==(GridCell a, GridCell b) noexcept { return a.x == b.x && a.y == b.y; }
inline bool operator!=(GridCell a, GridCell b) noexcept { return !(a == b); }

}  // namespace rtfuse::navigation
