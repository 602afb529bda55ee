#pragma once
// What the OctoMap reference test and benchmark share: OctoMap's real scan
// read as both libraries' clouds, and the comparison of a map with an
// OcTree voxel by voxel at the finest depth.
#include <octomap/octomap.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/point_cloud_file.hpp"
#include "mapping/occupancy_map.hpp"

namespace rtfuse::test {

// ../shared/data/octomap/scan.dat.bz2, decompressed by bzip2 into memory.
inline std::vector<mapping::MapPoint> read_octomap_scan(const std::string& shared_data) {
  const std::string path = shared_data + "/octomap/scan.dat.bz2";
  FILE* pipe = popen(("bzip2 -dc '" + path + "'").c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("cannot run bzip2 for " + path);
  std::string text;
  char buffer[1 << 16];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, n);
  if (pclose(pipe) != 0 || text.empty()) {
    throw std::runtime_error(path + ": bzip2 could not read it (apt-get install bzip2; is RTFUSE_SHARED_DATA right?)");
  }
  return apps::parse_xyz_cloud(text, path);
}

inline octomap::Pointcloud to_octomap(const std::vector<mapping::MapPoint>& points) {
  octomap::Pointcloud cloud;
  cloud.reserve(points.size());
  for (const auto& p : points) cloud.push_back(p.x, p.y, p.z);
  return cloud;
}

struct Difference {
  std::uint64_t octomap_voxels = 0;  // finest-depth voxels OctoMap knows
  std::uint64_t missing = 0;         // known to OctoMap, unknown here
  std::uint64_t different = 0;       // known to both, other log-odds bits
  std::string first;                 // the first difference, for the failure message
};

// Expands every OctoMap leaf to the voxels it stands for and looks each up.
inline Difference compare(const octomap::OcTree& tree, const mapping::OccupancyMap& map) {
  Difference d;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const unsigned span = 1u << (16 - it.getDepth());
    const octomap::OcTreeKey key = it.getKey();
    unsigned base[3];
    for (int i = 0; i < 3; ++i) base[i] = key[i] & ~(span - 1);
    const float expected = it->getLogOdds();
    for (unsigned a = 0; a < span; ++a)
      for (unsigned b = 0; b < span; ++b)
        for (unsigned c = 0; c < span; ++c) {
          mapping::VoxelKey k;
          k.k[0] = static_cast<std::uint16_t>(base[0] + a);
          k.k[1] = static_cast<std::uint16_t>(base[1] + b);
          k.k[2] = static_cast<std::uint16_t>(base[2] + c);
          ++d.octomap_voxels;
          float value;
          const bool known = map.log_odds(k, value);
          if (known && std::memcmp(&value, &expected, sizeof value) == 0) continue;
          (known ? d.different : d.missing) += 1;
          if (d.first.empty()) {
            d.first = "voxel " + std::to_string(k.k[0]) + " " + std::to_string(k.k[1]) + " " +
                      std::to_string(k.k[2]) + ": OctoMap " + std::to_string(expected) +
                      (known ? ", here " + std::to_string(value) : ", unknown here");
          }
        }
  }
  return d;
}

}  // namespace rtfuse::test
