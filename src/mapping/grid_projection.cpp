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

ProjectionCounts project_to_grid(const OccupancyMap& map, const GridSpec& spec, std::int8_t* cells) noexcept {
  const std::size_t n = spec.cells();
  std::fill(cells, cells + n, kCellUnknown);
  ProjectionCounts counts;
  if (n == 0) return counts;
  // The heights as a key range: voxels whose centre lies within them.
  const VoxelGrid& grid = map.grid();
  const double res = grid.resolution();
  const int z_lo = std::max(0, static_cast<int>(std::ceil(spec.z_min / res - 0.5)) + kKeyCentre);
  const int z_hi = std::min(65535, static_cast<int>(std::floor(spec.z_max / res - 0.5)) + kKeyCentre);
  const int x_lo = spec.first_x, x_hi = spec.first_x + spec.width - 1;
  const int y_lo = spec.first_y, y_hi = spec.first_y + spec.height - 1;
  const float occupied = map.log_odds().occupied;
  const BrickStore& store = map.store();
  for (std::uint32_t i = 0; i < store.bricks_used(); ++i) {
    const Brick& b = store.brick(i);
    const int bx = static_cast<int>(b.key & 0x1FFF) << kBrickShift;
    const int by = static_cast<int>(b.key >> 13 & 0x1FFF) << kBrickShift;
    const int bz = static_cast<int>(b.key >> 26 & 0x1FFF) << kBrickShift;
    if (bx > x_hi || bx + 7 < x_lo || by > y_hi || by + 7 < y_lo || bz > z_hi || bz + 7 < z_lo) continue;
    for (int s = 0; s < 8; ++s) {
      if (b.sub[s] == kUnknownBits) continue;
      const int sx = bx | (s & 1) << kSubShift, sy = by | (s >> 1 & 1) << kSubShift,
                sz = bz | (s >> 2 & 1) << kSubShift;
      for (int v = 0; v < kSubVoxels; ++v) {
        const int x = sx | (v & 3), y = sy | (v >> 2 & 3), z = sz | (v >> 4 & 3);
        if (x < x_lo || x > x_hi || y < y_lo || y > y_hi || z < z_lo || z > z_hi) continue;
        const std::uint32_t bits = store.value_bits(b, s, v);
        if (bits == kUnknownBits) continue;
        const std::int8_t state = OccupancyMap::float_of(bits) >= occupied ? kCellOccupied : kCellFree;
        std::int8_t& cell = cells[static_cast<std::size_t>(y - y_lo) * static_cast<std::size_t>(spec.width) +
                                  static_cast<std::size_t>(x - x_lo)];
        cell = std::max(cell, state);  // occupied over free over unknown
      }
    }
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

}  // namespace rtfuse::mapping
