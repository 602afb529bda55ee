#pragma once
// A 64-bit digest of a map's contents: every known voxel's key and log-odds
// bits. The same voxels give the same digest whatever order the bricks were
// made in (the bricks' digests are summed), so a replay, the other
// architecture or a map rebuilt from a file can be compared with one number.
#include <cstdint>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

std::uint64_t map_digest(const OccupancyMap& map) noexcept;

}  // namespace rtfuse::mapping
