#pragma once
// The 3-D map flattened to the 2-D occupancy grid a planner and ROS
// navigation use (nav_msgs/OccupancyGrid's convention, octomap_server's
// projection): a cell is 100 when a voxel of its column between two
// heights is occupied, 0 when the column has known voxels there and none
// occupied, -1 when it has none. Cells are the map's voxels, so the grid
// is given in voxel keys and no coordinate is rounded twice.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

inline constexpr std::int8_t kCellUnknown = -1;
inline constexpr std::int8_t kCellFree = 0;
inline constexpr std::int8_t kCellOccupied = 100;

struct GridSpec {
  std::uint16_t first_x = kKeyCentre;  // key of the voxel column of cell (0, 0)
  std::uint16_t first_y = kKeyCentre;
  int width = 0;                       // cells along x
  int height = 0;                      // cells along y; row 0 is the lowest y
  double z_min = -0.5;                 // m, voxel centres at or above
  double z_max = 2.0;                  // m, voxel centres at or below

  std::size_t cells() const noexcept { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};

// A width x height grid centred on the point (x, y) of a map, its columns
// aligned with the map's voxels.
GridSpec grid_around(const VoxelGrid& grid, double x, double y, int width, int height, double z_min, double z_max);

// The lower-left corner of cell (0, 0) in metres (OccupancyGrid's origin).
double grid_origin_x(const VoxelGrid& grid, const GridSpec& spec) noexcept;
double grid_origin_y(const VoxelGrid& grid, const GridSpec& spec) noexcept;

struct ProjectionCounts {
  std::size_t occupied = 0;
  std::size_t free = 0;
  std::size_t unknown = 0;
};

// Fills cells[spec.cells()], row by row from y's lowest row. Work is in the
// map's bricks, not in the grid's cells: a brick outside the grid or the
// heights costs a comparison.
ProjectionCounts project_to_grid(const OccupancyMap& map, const GridSpec& spec, std::int8_t* cells) noexcept;

// The same grid kept up to date: note_scan() after each insert_scan marks
// the grid's brick columns (8 x 8 cells) the scan wrote, refresh()
// projects those columns again from their bricks, each once however many
// scans wrote it. Its cost is what the scans since the last refresh
// touched, not the map.
class ProjectedGrid {
 public:
  // Allocates here, never after. Starts as the map's projection now.
  ProjectedGrid(const OccupancyMap& map, const GridSpec& spec);

  // After every insert_scan into the map (a scan missed is a grid wrong).
  void note_scan(const OccupancyMap& map) noexcept;
  // The grid of the map now: spec().cells() cells as project_to_grid's.
  const std::int8_t* refresh(const OccupancyMap& map) noexcept;

  const GridSpec& spec() const noexcept { return spec_; }

 private:
  GridSpec spec_;
  int column_x0_ = 0, column_y0_ = 0;  // brick coordinates of column 0
  int columns_x_ = 0, columns_y_ = 0;
  std::unique_ptr<std::int8_t[]> cells_;
  std::unique_ptr<std::uint32_t[]> dirty_;  // columns to project again, each once
  std::unique_ptr<std::uint8_t[]> is_dirty_;
  std::uint32_t dirty_count_ = 0;
};

}  // namespace rtfuse::mapping
