// OccupancyMap::fill_cube: writing known values over whole regions, for
// loading a map from a file of leaves rather than from scans.
#include <cstring>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

namespace {

// The sub-brick value slots hold bits; this is one voxel's.
std::uint32_t bits_of_value(float v) noexcept {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

}  // namespace

bool OccupancyMap::fill_cube(const VoxelKey& corner, int depth, float log_odds) noexcept {
  if (depth < 0 || depth > kTreeDepth || !(log_odds == log_odds)) return false;
  const int side_bits = kTreeDepth - depth;  // the cube is 2^side_bits voxels a side
  const std::uint32_t new_bits = bits_of_value(log_odds);
  const bool occupied_now = log_odds >= log_odds_.occupied;
  // Counts follow each voxel's change: unknown -> known, occupied flips.
  const auto account = [&](std::uint32_t old_bits, std::uint64_t voxels) {
    if (old_bits == kUnknownBits) {
      known_ += voxels;
      if (occupied_now) occupied_ += voxels;
      return;
    }
    const bool was = float_of(old_bits) >= log_odds_.occupied;
    if (was && !occupied_now) occupied_ -= voxels;
    if (!was && occupied_now) occupied_ += voxels;
  };
  const auto fill_sub = [&](Brick& b, int s) {
    const std::uint32_t slot = b.sub[s];
    if (is_dense(slot)) {
      const std::uint32_t* v = store_.block_values(block_of(slot));
      for (int i = 0; i < kSubVoxels; ++i) account(v[i], 1);
      store_.release_block(block_of(slot));
    } else {
      account(slot, kSubVoxels);
    }
    b.sub[s] = new_bits;
  };

  if (side_bits >= kBrickShift) {
    // Whole bricks: every sub-brick takes the value.
    const int bricks_bits = side_bits - kBrickShift;
    const std::uint32_t n = 1u << bricks_bits;
    const std::uint32_t bx0 = corner.k[0] >> kBrickShift, by0 = corner.k[1] >> kBrickShift,
                        bz0 = corner.k[2] >> kBrickShift;
    for (std::uint32_t z = 0; z < n; ++z) {
      for (std::uint32_t y = 0; y < n; ++y) {
        for (std::uint32_t x = 0; x < n; ++x) {
          const std::uint64_t key = static_cast<std::uint64_t>(bx0 + x) | static_cast<std::uint64_t>(by0 + y) << 13 |
                                    static_cast<std::uint64_t>(bz0 + z) << 26;
          const std::uint32_t index = store_.find_or_add(key);
          if (index == kNone) {
            dropped_ += 1;
            return false;
          }
          Brick& b = store_.brick(index);
          for (int s = 0; s < 8; ++s) fill_sub(b, s);
        }
      }
    }
    return true;
  }
  const std::uint32_t index = store_.find_or_add(brick_key_of(corner));
  if (index == kNone) {
    dropped_ += 1;
    return false;
  }
  Brick& b = store_.brick(index);
  if (side_bits == kSubShift) {
    fill_sub(b, sub_of(corner));
    return true;
  }
  // Inside one sub-brick: its voxels one by one, in a dense block.
  const int s = sub_of(corner);
  std::uint32_t slot = b.sub[s];
  if (!is_dense(slot)) {
    const std::uint32_t block = store_.new_block(slot);
    if (block == kNone) {
      dropped_ += 1;
      return false;
    }
    slot = b.sub[s] = dense_slot(block);
  }
  std::uint32_t* v = store_.block_values(block_of(slot));
  const int n = 1 << side_bits;
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        VoxelKey k = corner;
        k.k[0] = static_cast<std::uint16_t>(k.k[0] + x);
        k.k[1] = static_cast<std::uint16_t>(k.k[1] + y);
        k.k[2] = static_cast<std::uint16_t>(k.k[2] + z);
        std::uint32_t& cell = v[voxel_of(k)];
        account(cell, 1);
        cell = new_bits;
      }
    }
  }
  // A sub-brick now all one value gives its block back.
  bool uniform = true;
  for (int i = 1; i < kSubVoxels && uniform; ++i) uniform = v[i] == v[0];
  if (uniform && v[0] != kUnknownBits) {
    b.sub[s] = v[0];
    store_.release_block(block_of(slot));
  }
  return true;
}

}  // namespace rtfuse::mapping
