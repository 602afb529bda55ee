#pragma once
// Every cell a straight segment between two cell centres touches (its
// supercover): the cells whose closed square the segment meets, so where
// it passes exactly through a corner, all four cells around that corner.
// That is the rule that lets a segment be checked as the planner's graph
// checks a diagonal step (no corner cutting): a segment whose cells are all
// passable keeps the robot's centre in passable cells all along.
//
// Integer arithmetic only (the decision at each cell border is an exact
// cross-multiplication), so both architectures walk the same cells.
#include <cstdint>
#include <cstdlib>

#include "navigation/grid_cell.hpp"

namespace rtfuse::navigation {

// Calls visit(GridCell) for each cell from a to b, both included, in order
// along the segment; stops early, returning false, when visit returns false.
template <typename Visit>
bool walk_segment(GridCell a, GridCell b, Visit&& visit) {
  const std::int64_t nx = std::llabs(static_cast<std::int64_t>(b.x) - a.x);
  const std::int64_t ny = std::llabs(static_cast<std::int64_t>(b.y) - a.y);
  const int sx = b.x > a.x ? 1 : -1;
  const int sy = b.y > a.y ? 1 : -1;
  GridCell c = a;
  if (!visit(c)) return false;
  // ix, iy: borders crossed along x and y. The next x border is at
  // (ix + 0.5) / nx of the way, the next y border at (iy + 0.5) / ny:
  // compared as (1 + 2 ix) ny against (1 + 2 iy) nx.
  for (std::int64_t ix = 0, iy = 0; ix < nx || iy < ny;) {
    const std::int64_t decision = (1 + 2 * ix) * ny - (1 + 2 * iy) * nx;
    if (decision == 0) {  // through a corner: the two cells beside it too
      if (!visit(GridCell{c.x + sx, c.y}) || !visit(GridCell{c.x, c.y + sy})) return false;
      c.x += sx;
      c.y += sy;
      ++ix;
      ++iy;
    } else if (decision < 0) {
      c.x += sx;
      ++ix;
    } else {
      c.y += sy;
      ++iy;
    }
    if (!visit(c)) return false;
  }
  return true;
}

}  // namespace rtfuse::navigation
