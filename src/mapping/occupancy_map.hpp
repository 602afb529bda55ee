#pragma once
// A probabilistic 3-D occupancy map with OctoMap's update semantics, so it
// can be trusted exactly where OctoMap is: per scan, every voxel a ray
// crosses from the sensor to its end point (OctoMap's ray, end voxel
// excluded) is observed free, every end voxel occupied, a voxel hit in the
// scan is not also freed in it, and no voxel is updated twice in one scan.
// A ray longer than the maximum range frees up to that range and marks
// nothing. Voxel for voxel, the log-odds equal those of OcTree::
// insertPointCloud(cloud, origin, max_range, lazy_eval = false,
// discretize = false) as float32 (tests/reference/octomap_equality_test.cpp).
//
// It differs in how, not what: hits are applied first and every update
// marks its voxel in the brick's per-scan bitmask, where OctoMap gathers
// two hash sets of keys and subtracts one from the other; voxels live in
// a fixed pool of bricks (brick_store.hpp) instead of a pointer tree. No
// allocation after construction; a full pool drops the update, counted,
// and the map stops growing.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "mapping/brick_store.hpp"
#include "mapping/map_point.hpp"
#include "mapping/occupancy_params.hpp"
#include "mapping/scan_window.hpp"
#include "mapping/voxel_key.hpp"

namespace rtfuse::mapping {

// What one scan did.
struct ScanResult {
  std::uint32_t points = 0;        // given
  std::uint32_t rejected = 0;      // NaN or infinite coordinates, ignored
  std::uint32_t outside = 0;       // end point (or its ray) outside the map
  std::uint32_t beyond_range = 0;  // longer than the maximum range: freed up to it
  std::uint32_t hits = 0;          // voxels updated as occupied
  std::uint32_t frees = 0;         // voxels updated as free
  std::uint32_t dropped = 0;       // voxel updates lost to a full pool
};

class OccupancyMap {
 public:
  // Throws std::invalid_argument when check(params) finds fault or the
  // pool cannot be made.
  OccupancyMap(const OccupancyParams& params, BrickCapacity capacity);

  // Inserts one scan taken from origin; max_range < 0 means no limit.
  ScanResult insert_scan(const MapPoint* points, std::size_t count, const MapPoint& origin, double max_range = -1.0);

  // The log-odds of a voxel; false while it is unknown.
  bool log_odds(const VoxelKey& key, float& value) const noexcept;
  bool is_occupied(float log_odds) const noexcept { return log_odds >= log_odds_.occupied; }

  std::uint64_t known_voxels() const noexcept { return known_; }
  std::uint64_t occupied_voxels() const noexcept { return occupied_; }
  std::uint64_t dropped_updates() const noexcept { return dropped_; }
  std::uint64_t scans() const noexcept { return scans_; }

  const OccupancyParams& params() const noexcept { return params_; }
  const LogOdds& log_odds() const noexcept { return log_odds_; }
  const VoxelGrid& grid() const noexcept { return grid_; }
  const BrickStore& store() const noexcept { return store_; }

  // The bricks the last insert_scan wrote (indices into store()), each
  // once, until the next scan or clear(): what a digest or a grid kept up
  // to date scan by scan has to look at again.
  const std::uint32_t* scan_bricks() const noexcept { return touched_.get(); }
  std::uint32_t scan_brick_count() const noexcept { return touched_count_; }

  // visit(const VoxelKey&, float log_odds) for every known voxel, brick by
  // brick in the order they were made (deterministic, not sorted).
  template <class Visit>
  void for_each_voxel(Visit&& visit) const {
    for (std::uint32_t i = 0; i < store_.bricks_used(); ++i) {
      const Brick& b = store_.brick(i);
      const int bx = static_cast<int>(b.key & 0x1FFF) << kBrickShift;
      const int by = static_cast<int>(b.key >> 13 & 0x1FFF) << kBrickShift;
      const int bz = static_cast<int>(b.key >> 26 & 0x1FFF) << kBrickShift;
      for (int s = 0; s < 8; ++s) {
        if (b.sub[s] == kUnknownBits) continue;
        for (int v = 0; v < kSubVoxels; ++v) {
          const std::uint32_t bits = store_.value_bits(b, s, v);
          if (bits == kUnknownBits) continue;
          VoxelKey key;
          key.k[0] = static_cast<std::uint16_t>(bx | (s & 1) << kSubShift | (v & 3));
          key.k[1] = static_cast<std::uint16_t>(by | (s >> 1 & 1) << kSubShift | (v >> 2 & 3));
          key.k[2] = static_cast<std::uint16_t>(bz | (s >> 2 & 1) << kSubShift | (v >> 4 & 3));
          visit(key, float_of(bits));
        }
      }
    }
  }

  // Forgets every voxel and count (the pool stays).
  void clear() noexcept;
  // The pool's pages made resident (BrickStore::prefault), for a daemon.
  void prefault() noexcept { store_.prefault(); }

  // Sets every voxel of the cube of 2^(16 - depth) voxels a side whose
  // lowest corner is `corner` (aligned to the cube's size) to log_odds,
  // known: how a map is loaded from a file of leaves (octomap_binary_reader).
  // Whole sub-bricks take one slot, so a coarse leaf costs its bricks, not
  // its voxels. False, with the map changed up to there and the shortfall
  // counted in dropped_updates(), when the pool cannot hold it.
  bool fill_cube(const VoxelKey& corner, int depth, float log_odds) noexcept;

  static float float_of(std::uint32_t bits) noexcept {
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }

 private:
  class ScanWriter;

  void compact_touched() noexcept;

  OccupancyParams params_;
  LogOdds log_odds_;
  VoxelGrid grid_;
  BrickStore store_;
  ScanWindow window_;  // the scan's visited voxels near the sensor
  std::unique_ptr<std::uint32_t[]> touched_;  // bricks touched in this scan
  std::uint32_t touched_count_ = 0;
  std::uint32_t scan_ = 0;
  std::uint64_t scans_ = 0;
  std::uint64_t known_ = 0;
  std::uint64_t occupied_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace rtfuse::mapping
