#pragma once
// Whether the path just ahead of the robot runs into what the costmap
// now says is an obstacle: the check that makes the follower stop when
// the map reveals one on its path (the planner routes around it later).
#include <cstdint>

#include "navigation/cost_values.hpp"
#include "navigation/pose2.hpp"

namespace rtfuse::navigation {

// Where a cost grid lies in the odom frame: the lower-left corner of cell
// (0, 0) (nav_msgs/OccupancyGrid's origin, no rotation) and the cell size.
struct GridGeometry {
  double origin_x = 0.0;
  double origin_y = 0.0;
  double resolution = 0.05;
};

// True when the path from `from` (on the segment from path[from_index] to
// the next: the follower's nearest point) through path[from_index + 1],
// ... for check_distance_m along it touches a cell whose cost is at or
// above lethal_from, or leaves the grid. The last piece is cut at exactly
// check_distance_m; an infinite distance checks to the path's end. A
// piece touches the cells whose closed square it meets (its supercover),
// decided exactly in fixed point (2^-16 of a cell on grids up to 16384
// cells a side) with integers only: a piece through a corner or along a
// border counts the cells on both sides; between cell centres these are
// the cells grid_line.hpp's walk visits, the planner's and the smoother's.
//
// Unknown cells (255) are at or above every lethal_from: the robot does
// not drive into what it has not seen, nor off its map. Conservative by
// construction: true also when it cannot tell (no grid, a bad geometry or
// lethal_from of 0, n < 1, from_index outside [0, n), a point not
// usable(), a NaN distance). Allocates nothing; the work is bounded by the
// cells within check_distance_m plus the path's repeated points.
bool path_blocked(const CostView& costs, const GridGeometry& geometry, const Point2* path, int n, int from_index,
                  Point2 from, double check_distance_m, std::uint8_t lethal_from) noexcept;

}  // namespace rtfuse::navigation
