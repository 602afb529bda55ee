#pragma once
// The costmap a planner reads, from the mapper's 2-D occupancy grid, with
// costmap_2d's static and inflation layers' semantics: an obstacle cell
// (grid value >= occupied_from) costs 254; a cell whose centre is within
// the inscribed radius of an obstacle cell's centre 253; within the
// inflation radius 252 exp(-k (d - inscribed)), truncated; beyond, its own
// cost (0 free; unknown as CostmapParams::unknown says). An unknown cell
// takes an inflated cost only at 253 or more (costmap_2d's default
// inflate_unknown = false). d is the exact distance to the nearest obstacle
// cell, in cells times the resolution, where costmap_2d's wavefront can be
// a cell's rounding off on diagonals; a cell within the radius in cells
// (costmap_2d's cell_inflation_radius, the radius over the resolution
// rounded up) is inflated.
//
// Kept up to date: update() compares the new grid with the last one and
// redoes only the 16 x 16-cell tiles within the inflation radius of a cell
// that changed, so a map that grows at its edges costs what it changed.
// Fixed size; allocates in the constructor only.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "navigation/cost_values.hpp"
#include "navigation/costmap_params.hpp"

namespace rtfuse::navigation {

class Costmap {
 public:
  // width x height cells, as the occupancy grid it is made from. Throws
  // std::invalid_argument when check(params) finds fault or the size is
  // not positive.
  Costmap(int width, int height, const CostmapParams& params);
  ~Costmap();

  // Every cost anew from the grid's width x height cells (nav_msgs/
  // OccupancyGrid values: -1 unknown, 0..100, row-major from the lowest y).
  void set_grid(const std::int8_t* cells) noexcept;
  // The costs where the grid changed since the last set_grid or update:
  // returns the cells whose kind (free, obstacle, unknown) changed.
  std::size_t update(const std::int8_t* cells) noexcept;

  CostView view() const noexcept { return CostView{cost_.get(), width_, height_}; }
  std::uint8_t cost(int x, int y) const noexcept { return view().at(x, y); }
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  const CostmapParams& params() const noexcept { return params_; }
  // The inflation radius in cells (costmap_2d's cell_inflation_radius).
  int radius_cells() const noexcept { return radius_; }
  // Tiles the last update redid (for its benchmark and tests).
  std::size_t tiles_redone() const noexcept { return tiles_redone_; }

 private:
  std::uint8_t kind_of(std::int8_t value) const noexcept;
  // Recomputes the costs of the cells [x0, x1) x [y0, y1).
  void redo(int x0, int y0, int x1, int y1) noexcept;

  int width_ = 0;
  int height_ = 0;
  CostmapParams params_;
  int radius_ = 0;                             // in cells
  std::unique_ptr<std::int8_t[]> grid_;        // the grid last given, to find what changed
  std::unique_ptr<std::uint8_t[]> kind_;       // per cell: free, obstacle, unknown
  std::unique_ptr<std::uint8_t[]> cost_;       // per cell
  std::unique_ptr<std::uint8_t[]> cost_at_;    // by squared distance in cells, 0..radius^2
  std::unique_ptr<std::uint16_t[]> vertical_;  // workspace: distance to the nearest obstacle up or down a column
  int tiles_x_ = 0, tiles_y_ = 0;
  std::unique_ptr<std::uint8_t[]> dirty_;  // per tile
  std::unique_ptr<std::uint32_t[]> dirty_list_;
  std::size_t tiles_redone_ = 0;
};

}  // namespace rtfuse::navigation
