#pragma once
// A planned path with the waypoints a straight line can skip removed:
// from each kept waypoint, the next kept one is the farthest of the
// following waypoints reached before the first whose straight segment
// touches a cell that is not passable (every cell the segment touches, its
// supercover: grid_line.hpp). Every segment of the result therefore keeps
// the robot's centre in passable cells, corners included, the same cells
// the planner's graph allows: smoothing never makes a path collide.
//
// What it does not promise: a lower cost. A segment may cross cells of
// higher cost (inflation) that the planned path went around; it stays
// passable, and a follower that weighs cost can keep the planned cells.
#include <cstddef>

#include "navigation/cost_values.hpp"
#include "navigation/grid_cell.hpp"
#include "navigation/passability.hpp"

namespace rtfuse::navigation {

// True when every cell the segment from a to b touches is inside the grid
// and passable.
bool segment_passable(const CostView& grid, const Passability& rule, GridCell a, GridCell b) noexcept;

// Writes the kept waypoints of path[0..cells) to out (which may be path
// itself), the first and the last always, and returns their number
// (cells when cells < 3). Pure and allocation-free: out must hold cells.
// Consecutive input cells are expected to be neighbours on passable cells
// (a planner's path); a segment that is not clear is never skipped, so a
// bad input comes back with its bad steps as they were.
std::size_t smooth_path(const CostView& grid, const Passability& rule, const GridCell* path, std::size_t cells,
                        GridCell* out) noexcept;

}  // namespace rtfuse::navigation
