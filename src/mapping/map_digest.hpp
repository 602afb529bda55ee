#pragma once
// A 64-bit digest of a map's contents: every known voxel's key and log-odds
// bits. The same voxels give the same digest whatever order the bricks were
// made in (the bricks' digests are summed), so a replay, the other
// architecture or a map rebuilt from a file can be compared with one number.
#include <cstdint>
#include <memory>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

std::uint64_t map_digest(const OccupancyMap& map) noexcept;

// The same digest kept up to date: note_scan() after each insert_scan marks
// the bricks the scan wrote, refresh() hashes those again, each once however
// many scans wrote it. Its cost is what the scans since the last refresh
// touched, not the map (map_digest walks every brick: tens of milliseconds
// once a drive has mapped millions of voxels).
class MapDigest {
 public:
  // Sized for the map's pool; allocates here, never after. Starts from the
  // map as it is.
  explicit MapDigest(const OccupancyMap& map);

  // After every insert_scan into the map (a scan missed is a digest wrong).
  void note_scan(const OccupancyMap& map) noexcept;
  // The digest of the map now.
  std::uint64_t refresh(const OccupancyMap& map) noexcept;
  // From the whole map: after clear() or loading leaves with fill_cube.
  void rebuild(const OccupancyMap& map) noexcept;

 private:
  std::unique_ptr<std::uint64_t[]> brick_digest_;  // each brick's share of sum_
  std::unique_ptr<std::uint32_t[]> dirty_;         // bricks to hash again, each once
  std::unique_ptr<std::uint8_t[]> is_dirty_;
  std::uint32_t dirty_count_ = 0;
  std::uint32_t bricks_ = 0;  // entries of brick_digest_ in use
  std::uint64_t sum_ = 0;
};

}  // namespace rtfuse::mapping
