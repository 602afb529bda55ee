// rtfuse-map: builds an occupancy map offline and writes it as OctoMap's
// .bt. This first mode takes one point cloud (x y z a line, OctoMap's
// scan.dat format) seen from one origin:
//
//   rtfuse-map --cloud SCAN.xyz --origin X,Y,Z --resolution R
//              [--max-range M] [--repeat K] [--pool-mib N] --out MAP.bt
//
// The cloud is inserted K times, each into an emptied map (the figure is
// the median), and the last map written. The last stdout line is a JSON
// object: points, ms_median, known and occupied voxels, memory_bytes (the
// map's bytes in use, comparable with OctoMap's memoryUsage()), the pool,
// the file and the map's digest.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/point_cloud_file.hpp"
#include "mapping/map_digest.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/occupancy_map.hpp"

namespace {

using namespace rtfuse::mapping;

bool parse_origin(const std::string& text, MapPoint& origin) {
  char tail = 0;
  return std::sscanf(text.c_str(), "%f,%f,%f%c", &origin.x, &origin.y, &origin.z, &tail) == 3 && is_finite(origin);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtfuse-map: an occupancy map (OctoMap's semantics) built offline, written as .bt"};
  std::string cloud_path, origin_text = "0,0,0", out_path;
  double resolution = 0.05, max_range = -1.0;
  int repeat = 1;
  std::size_t pool_mib = 512;
  app.add_option("--cloud", cloud_path, "point cloud, one \"x y z\" (metres) a line, as OctoMap's scan.dat")
      ->required();
  app.add_option("--origin", origin_text, "the sensor's position X,Y,Z in the cloud's frame (metres)");
  app.add_option("--resolution", resolution, "voxel edge (metres)");
  app.add_option("--max-range", max_range,
                 "rays longer than this free up to it and mark nothing (metres; negative: no limit)");
  app.add_option("--repeat", repeat, "insert the cloud this many times into an emptied map; ms_median over them")
      ->check(CLI::Range(1, 1000));
  app.add_option("--pool-mib", pool_mib, "memory reserved for the map (MiB); a full pool drops updates, counted")
      ->check(CLI::Range(1, 1 << 20));
  app.add_option("-o,--out", out_path, "the map as OctoMap's binary tree (.bt)")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  MapPoint origin;
  if (!parse_origin(origin_text, origin)) {
    std::fprintf(stderr, "rtfuse-map: --origin \"%s\": expected three finite numbers X,Y,Z\n", origin_text.c_str());
    return 2;
  }
  OccupancyParams params;
  params.resolution = resolution;
  if (const std::string fault = check(params); !fault.empty()) {
    std::fprintf(stderr, "rtfuse-map: --resolution: %s\n", fault.c_str());
    return 2;
  }

  std::vector<MapPoint> cloud;
  try {
    cloud = rtfuse::apps::read_xyz_cloud(cloud_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rtfuse-map: %s\n", e.what());
    return 1;
  }
  if (cloud.empty()) {
    std::fprintf(stderr, "rtfuse-map: %s: no points\n", cloud_path.c_str());
    return 1;
  }

  const BrickCapacity capacity = capacity_for_bytes(pool_mib << 20);
  OccupancyMap map(params, capacity);
  std::vector<double> ms;
  ScanResult result;
  for (int k = 0; k < repeat; ++k) {
    map.clear();
    const auto t0 = std::chrono::steady_clock::now();
    result = map.insert_scan(cloud.data(), cloud.size(), origin, max_range);
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.size() % 2 ? sorted[sorted.size() / 2]
                                          : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);

  OctomapBinaryWriter writer(capacity.bricks);
  std::vector<std::uint8_t> file;
  const std::size_t nodes = writer.write(map, file);
  {
    std::ofstream out(out_path, std::ios::binary);
    if (!out || !out.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size())) ||
        !out.flush()) {
      std::fprintf(stderr, "rtfuse-map: %s: cannot write: %s\n", out_path.c_str(), std::strerror(errno));
      return 1;
    }
  }
  if (result.dropped > 0) {
    std::fprintf(stderr,
                 "rtfuse-map: the pool (%zu MiB) is full: %u voxel updates dropped, the map is incomplete; "
                 "raise --pool-mib\n",
                 pool_mib, result.dropped);
  }
  if (result.rejected > 0) std::fprintf(stderr, "rtfuse-map: %u points not finite, skipped\n", result.rejected);

  std::printf(
      "{\"mode\": \"cloud\", \"cloud\": \"%s\", \"points\": %zu, \"origin\": [%.9g, %.9g, %.9g], "
      "\"resolution\": %.9g, \"max_range\": %.9g, \"repeat\": %d, \"ms_median\": %.3f, \"ms_min\": %.3f, "
      "\"hits\": %u, \"frees\": %u, \"beyond_range\": %u, \"outside\": %u, \"rejected\": %u, "
      "\"known_voxels\": %" PRIu64 ", \"occupied_voxels\": %" PRIu64 ", \"dropped_updates\": %u, "
      "\"memory_bytes\": %zu, \"pool_bytes\": %zu, \"bt\": \"%s\", \"bt_bytes\": %zu, \"bt_nodes\": %zu, "
      "\"digest\": \"%016" PRIx64 "\"}\n",
      cloud_path.c_str(), cloud.size(), origin.x, origin.y, origin.z, resolution, max_range, repeat, median, sorted[0],
      result.hits, result.frees, result.beyond_range, result.outside, result.rejected, map.known_voxels(),
      map.occupied_voxels(), result.dropped, map.store().bytes_used(), map.store().bytes_reserved(), out_path.c_str(),
      file.size(), nodes, map_digest(map));
  return result.dropped > 0 ? 3 : 0;
}
