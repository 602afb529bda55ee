#include "navigation/path_smoother.hpp"

#include "navigation/grid_line.hpp"

namespace rtfuse::navigation {

bool segment_passable(const CostView& grid, const Passability& rule, GridCell a, GridCell b) noexcept {
  if (!grid.valid()) return false;
  return walk_segment(a, b, [&](GridCell c) noexcept {
    return c.x >= 0 && c.y >= 0 && c.x < grid.width && c.y < grid.height && rule.passable(grid.at(c.x, c.y));
  });
}

std::size_t smooth_path(const CostView& grid, const Passability& rule, const GridCell* path, std::size_t cells,
                        GridCell* out) noexcept {
  if (cells == 0) return 0;
  if (cells < 3) {
    for (std::size_t i = 0; i < cells; ++i) out[i] = path[i];
    return cells;
  }
  // out[kept] never runs ahead of the input index read next, so out may be
  // path: the anchor is kept by value.
  std::size_t kept = 0;
  GridCell anchor = path[0];
  out[kept++] = anchor;
  std::size_t i = 0;  // the anchor's index in path
  while (i + 1 < cells) {
    std::size_t j = i + 1;  // the farthest waypoint reachable straight from the anchor so far
    while (j + 1 < cells && segment_passable(grid, rule, anchor, path[j + 1])) ++j;
    anchor = path[j];
    out[kept++] = anchor;
    i = j;
  }
  return kept;
}

}  // namespace rtfuse::navigation
