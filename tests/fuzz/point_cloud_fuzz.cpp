// rtfuse-map's point cloud reader (x y z a line) and what the cloud goes
// into: the occupancy map and its .bt writer.
// Property: refused with "cloud.xyz:<line>: what", or finite points; their
// scan (from the origin, 20 m range: bounded work) leaves a map with no
// NaN, no more known voxels than the pool holds, and a .bt file whose
// header counts the nodes it holds.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/point_cloud_file.hpp"
#include "fuzz_check.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/occupancy_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rtfuse::mapping;
  std::vector<MapPoint> cloud;
  try {
    cloud = rtfuse::apps::parse_xyz_cloud(std::string(reinterpret_cast<const char*>(data), size), "cloud.xyz");
  } catch (const std::runtime_error& e) {
    FUZZ_CHECK(std::string(e.what()).rfind("cloud.xyz:", 0) == 0, "the error names the file and line");
    return 0;
  }
  for (const MapPoint& p : cloud) FUZZ_CHECK(is_finite(p), "finite points");
  OccupancyParams params;
  params.resolution = 0.2;
  static OccupancyMap map(params, BrickCapacity{16, 64});
  static OctomapBinaryWriter writer(16);
  map.clear();
  const ScanResult r = map.insert_scan(cloud.data(), cloud.size(), {0.1f, -0.1f, 0.0f}, 20.0);
  FUZZ_CHECK(r.rejected == 0, "parsed points are finite");
  FUZZ_CHECK(map.known_voxels() <= 16u * 512u, "no more voxels than the pool holds");
  std::uint64_t known = 0;
  map.for_each_voxel([&](const VoxelKey&, float v) {
    FUZZ_CHECK(!std::isnan(v), "no NaN in the map");
    ++known;
  });
  FUZZ_CHECK(known == map.known_voxels(), "the count is the voxels");
  std::vector<std::uint8_t> bt;
  const std::size_t nodes = writer.write(map, bt);
  FUZZ_CHECK(nodes == 0 || bt.size() >= 2 * (nodes - 1) / 8, "a file as long as its tree");
  return 0;
}
