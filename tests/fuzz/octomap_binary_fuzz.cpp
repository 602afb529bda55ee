// The .bt reader (rtfuse-map --bt; OctoMap's binary tree files).
// Property: refused with "map.bt: what", or a map of the file's leaves:
// no NaN, every value one of the two clamps, counts that are the voxels,
// no more bricks than the pool; and the map written back reads again.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_check.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/octomap_binary_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rtfuse::mapping;
  OctomapBinaryHeader header;
  std::string error;
  if (!read_octomap_binary_header(data, size, "map.bt", &header, &error)) {
    FUZZ_CHECK(error.rfind("map.bt", 0) == 0, "the error names the file");
    return 0;
  }
  OccupancyParams params;
  params.resolution = header.resolution;
  if (!check(params).empty()) return 0;
  static const BrickCapacity pool{32, 128};
  OccupancyMap map(params, pool);
  if (!read_octomap_binary(data, size, "map.bt", map, &error)) {
    FUZZ_CHECK(error.rfind("map.bt", 0) == 0, "the error names the file");
  }
  FUZZ_CHECK(map.store().bricks_used() <= pool.bricks, "within the pool");
  std::uint64_t known = 0, occupied = 0;
  map.for_each_voxel([&](const VoxelKey&, float v) {
    FUZZ_CHECK(!std::isnan(v), "no NaN");
    FUZZ_CHECK(v == map.log_odds().clamp_max || v == map.log_odds().clamp_min, "leaves load at the clamps");
    ++known;
    occupied += v >= map.log_odds().occupied;
  });
  FUZZ_CHECK(known == map.known_voxels() && occupied == map.occupied_voxels(), "the counts are the voxels");
  if (error.empty()) {
    OctomapBinaryWriter writer(pool.bricks);
    std::vector<std::uint8_t> again;
    writer.write(map, again);
    OccupancyMap back(params, pool);
    FUZZ_CHECK(read_octomap_binary(again.data(), again.size(), "map.bt", back, &error), "the map written reads");
    FUZZ_CHECK(back.known_voxels() == map.known_voxels(), "and holds the same voxels");
  }
  return 0;
}
