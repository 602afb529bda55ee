#include "mapping/grid_projection.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::mapping {

GridSpec grid_around(const VoxelGrid& grid, double x, double y, int width, int height, double z_min, double z_max) {
  GridSpec spec;
  std::uint16_t cx = kKeyCentre, cy = kKeyCentre;
  grid.key_of(x, cx);
  grid.key_of(y, cy);
  const int fx = std::clamp(static_cast<int>(cx) - width / 2, 0, 65536 - std::max(width, 1));
  const int fy = std::clamp(static_cast<int>(cy) - height / 2, 0, 65536 - std::max(height, 1));
  spec.first_x = static_cast<std::uint16_t>(fx);
  spec.first_y = static_cast<std::uint16_t>(fy);
  spec.width = width;
  spec.height = height;
  spec.z_min = z_min;
  spec.z_max = z_max;
  return spec;
}

double grid_origin_x(const VoxelGrid& grid, const GridSpec& spec) noexcept {
  return (static_cast<double>(spec.first_x) - kKeyCentre) * grid.resolution();
}
double grid_origin_y(const VoxelGrid& grid, const GridSpec& spec) noexcept {
  return (static_cast<double>(spec.first_y) - kKeyCentre) * grid.resolution();
}

namespace {

// The grid's bounds as key ranges: voxels whose centre lies within the
// heights, columns within the grid.
struct KeyBox {
  int x_lo, x_hi, y_lo, y_hi, z_lo, z_hi;
};

KeyBox key_box(const VoxelGrid& grid, const GridSpec& spec) noexcept {
  const double res = grid.resolution();
  KeyBox k;
  k.z_lo = std::max(0, static_cast<int>(std::ceil(spec.z_min / res - 0.5)) + kKeyCentre);
  k.z_hi = std::min(65535, static_cast<int>(std::floor(spec.z_max / res - 0.5)) + kKeyCentre);
  k.x_lo = spec.first_x, k.x_hi = spec.first_x + spec.width - 1;
  k.y_lo = spec.first_y, k.y_hi = spec.first_y + spec.height - 1;
  return k;
}

int brick_x(const Brick& b) noexcept { return static_cast<int>(b.key & 0x1FFF) << kBrickShift; }
int brick_y(const Brick& b) noexcept { return static_cast<int>(b.key >> 13 & 0x1FFF) << kBrickShift; }
int brick_z(const Brick& b) noexcept { return static_cast<int>(b.key >> 26 & 0x1FFF) << kBrickShift; }

// A brick's voxels within the box raise their cells: occupied over free
// over unknown.
void project_brick(const BrickStore& store, const Brick& b, const KeyBox& box, int width, float occupied,
                   std::int8_t* cells) noexcept {
  const int bx = brick_x(b), by = brick_y(b), bz = brick_z(b);
  if (bx > box.x_hi || bx + 7 < box.x_lo || by > box.y_hi || by + 7 < box.y_lo || bz > box.z_hi ||
      bz + 7 < box.z_lo) {
    return;
  }
  for (int s = 0; s < 8; ++s) {
    if (b.sub[s] == kUnknownBits) continue;
    const int sx = bx | (s & 1) << kSubShift, sy = by | (s >> 1 & 1) << kSubShift, sz = bz | (s >> 2 & 1) << kSubShift;
    for (int v = 0; v < kSubVoxels; ++v) {
      const int x = sx | (v & 3), y = sy | (v >> 2 & 3), z = sz | (v >> 4 & 3);
      if (x < box.x_lo || x > box.x_hi || y < box.y_lo || y > box.y_hi || z < box.z_lo || z > box.z_hi) continue;
      const std::uint32_t bits = store.value_bits(b, s, v);
      if (bits == kUnknownBits) continue;
      const std::int8_t state = OccupancyMap::float_of(bits) >= occupied ? kCellOccupied : kCellFree;
      std::int8_t& cell = cells[static_cast<std::size_t>(y - box.y_lo) * static_cast<std::size_t>(width) +
                                static_cast<std::size_t>(x - box.x_lo)];
      cell = std::max(cell, state);
    }
  }
}

}  // namespace

ProjectionCounts project_to_grid(const OccupancyMap& map, const GridSpec& spec, std::int8_t* cells) noexcept {
  const std::size_t n = spec.cells();
  std::fill(cells, cells + n, kCellUnknown);
  ProjectionCounts counts;
  if (n == 0) return counts;
  const KeyBox box = key_box(map.grid(), spec);
  const float occupied = map.log_odds().occupied;
  const BrickStore& store = map.store();
  for (std::uint32_t i = 0; i < store.bricks_used(); ++i) {
    project_brick(store, store.brick(i), box, spec.width, occupied, cells);
  }
  for (std::size_t c = 0; c < n; ++c) {
    if (cells[c] == kCellOccupied) {
      ++counts.occupied;
    } else if (cells[c] == kCellFree) {
      ++counts.free;
    } else {
      ++counts.unknown;
    }
  }
  return counts;
}

ProjectedGrid::ProjectedGrid(const OccupancyMap& map, const GridSpec& spec) : spec_(spec) {
  const KeyBox box = key_box(map.grid(), spec);
  column_x0_ = box.x_lo >> kBrickShift, column_y0_ = box.y_lo >> kBrickShift;
  columns_x_ = spec.width > 0 ? (box.x_hi >> kBrickShift) - column_x0_ + 1 : 0;
  columns_y_ = spec.height > 0 ? (box.y_hi >> kBrickShift) - column_y0_ + 1 : 0;
  const std::size_t columns = static_cast<std::size_t>(columns_x_) * static_cast<std::size_t>(columns_y_);
  cells_.reset(new std::int8_t[spec.cells()]);
  dirty_.reset(new std::uint32_t[columns]);
  is_dirty_.reset(new std::uint8_t[columns]());
  project_to_grid(map, spec, cells_.get());
}

void ProjectedGrid::note_scan(const OccupancyMap& map) noexcept {
  if (spec_.cells() == 0) return;
  const KeyBox box = key_box(map.grid(), spec_);
  const BrickStore& store = map.store();
  const std::uint32_t* bricks = map.scan_bricks();
  for (std::uint32_t i = 0; i < map.scan_brick_count(); ++i) {
    const Brick& b = store.brick(bricks[i]);
    const int bz = brick_z(b);
    if (bz > box.z_hi || bz + 7 < box.z_lo) continue;
    const int cx = (brick_x(b) >> kBrickShift) - column_x0_, cy = (brick_y(b) >> kBrickShift) - column_y0_;
    if (cx < 0 || cy < 0 || cx >= columns_x_ || cy >= columns_y_) continue;
    const std::uint32_t c = static_cast<std::uint32_t>(cy * columns_x_ + cx);
    if (is_dirty_[c]) continue;
    is_dirty_[c] = 1;
    dirty_[dirty_count_++] = c;
  }
}

const std::int8_t* ProjectedGrid::refresh(const OccupancyMap& map) noexcept {
  const KeyBox box = key_box(map.grid(), spec_);
  const float occupied = map.log_odds().occupied;
  const BrickStore& store = map.store();
  for (std::uint32_t i = 0; i < dirty_count_; ++i) {
    const std::uint32_t c = dirty_[i];
    is_dirty_[c] = 0;
    const int bx = (column_x0_ + static_cast<int>(c) % columns_x_) << kBrickShift;
    const int by = (column_y0_ + static_cast<int>(c) / columns_x_) << kBrickShift;
    // The column's cells from unknown again, then every brick of it
    // between the heights.
    const int x_lo = std::max(box.x_lo, bx), x_hi = std::min(box.x_hi, bx + 7);
    const int y_lo = std::max(box.y_lo, by), y_hi = std::min(box.y_hi, by + 7);
    for (int y = y_lo; y <= y_hi; ++y) {
      std::int8_t* row = cells_.get() + static_cast<std::size_t>(y - box.y_lo) * static_cast<std::size_t>(spec_.width);
      std::fill(row + (x_lo - box.x_lo), row + (x_hi - box.x_lo) + 1, kCellUnknown);
    }
    const std::uint64_t column_key =
        static_cast<std::uint64_t>(bx >> kBrickShift) | static_cast<std::uint64_t>(by >> kBrickShift) << 13;
    for (int z = box.z_lo & ~7; z <= box.z_hi; z += 8) {
      const std::uint32_t index = store.find(column_key | static_cast<std::uint64_t>(z >> kBrickShift) << 26);
      if (index != kNone) project_brick(store, store.brick(index), box, spec_.width, occupied, cells_.get());
    }
  }
  dirty_count_ = 0;
  return cells_.get();
}

}  // namespace rtfuse::mapping
