// rtfuse-map: builds an occupancy map offline and writes it as OctoMap's
// .bt. This first mode takes one point cloud (x y z a line, OctoMap's
// scan.dat format) seen from one origin:
//
//   rtfuse-map --cloud SCAN.xyz --origin X,Y,Z --resolution R
//              [--max-range M] [--repeat K] [--pool-mib N] --out MAP.bt
//              [--grid PREFIX [--z-min A] [--z-max B]]
//
// The cloud is inserted K times, each into an emptied map (the figure is
// the median), and the last map written. The last stdout line is a JSON
// object: points, ms_median, known and occupied voxels, memory_bytes (the
// map's bytes in use, comparable with OctoMap's memoryUsage()), the pool,
// the file and the map's digest. --grid also writes the 2-D projection
// between two heights over everything known, as map_server's PREFIX.pgm
// and PREFIX.yaml.
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
#include "mapping/grid_projection.hpp"
#include "mapping/map_server_files.hpp"
#include "mapping/map_digest.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/occupancy_map.hpp"

namespace {

using namespace rtfuse::mapping;

bool write_file(const std::string& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary);
  if (!out || !out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size)) || !out.flush()) {
    std::fprintf(stderr, "rtfuse-map: %s: cannot write: %s\n", path.c_str(), std::strerror(errno));
    return false;
  }
  return true;
}

// The smallest grid holding every known voxel column between the heights.
GridSpec grid_of_known(const OccupancyMap& map, double z_min, double z_max) {
  int x0 = 65536, y0 = 65536, x1 = -1, y1 = -1;
  map.for_each_voxel([&](const VoxelKey& k, float) {
    const double z = map.grid().centre(k.k[2]);
    if (z < z_min || z > z_max) return;
    x0 = std::min(x0, int{k.k[0]});
    x1 = std::max(x1, int{k.k[0]});
    y0 = std::min(y0, int{k.k[1]});
    y1 = std::max(y1, int{k.k[1]});
  });
  GridSpec spec;
  spec.z_min = z_min;
  spec.z_max = z_max;
  if (x1 < 0) return spec;  // nothing known there: an empty grid
  spec.first_x = static_cast<std::uint16_t>(x0);
  spec.first_y = static_cast<std::uint16_t>(y0);
  spec.width = x1 - x0 + 1;
  spec.height = y1 - y0 + 1;
  return spec;
}

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
  std::string grid_prefix;
  double z_min = -0.5, z_max = 2.0;
  app.add_option("--grid", grid_prefix, "also write the 2-D grid as map_server's PREFIX.pgm and PREFIX.yaml");
  app.add_option("--z-min", z_min, "the grid's lowest voxel centres (metres)");
  app.add_option("--z-max", z_max, "the grid's highest voxel centres (metres)");
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
  if (!write_file(out_path, file.data(), file.size())) return 1;
  ProjectionCounts grid_counts;
  GridSpec spec;
  if (!grid_prefix.empty()) {
    if (!(z_min <= z_max)) {
      std::fprintf(stderr, "rtfuse-map: --z-min %g is above --z-max %g\n", z_min, z_max);
      return 2;
    }
    spec = grid_of_known(map, z_min, z_max);
    std::vector<std::int8_t> cells(spec.cells());
    grid_counts = project_to_grid(map, spec, cells.data());
    const std::vector<std::uint8_t> pgm = map_server_pgm(cells.data(), spec.width, spec.height);
    const std::string image = grid_prefix + ".pgm";
    const std::string base = image.substr(image.find_last_of('/') + 1);
    const std::string yaml = map_server_yaml(base, map.grid().resolution(), grid_origin_x(map.grid(), spec),
                                             grid_origin_y(map.grid(), spec));
    if (!write_file(image, pgm.data(), pgm.size()) ||
        !write_file(grid_prefix + ".yaml", yaml.data(), yaml.size())) {
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
      "\"digest\": \"%016" PRIx64 "\", \"grid_width\": %d, \"grid_height\": %d, \"grid_occupied\": %zu, "
      "\"grid_free\": %zu}\n",
      cloud_path.c_str(), cloud.size(), origin.x, origin.y, origin.z, resolution, max_range, repeat, median, sorted[0],
      result.hits, result.frees, result.beyond_range, result.outside, result.rejected, map.known_voxels(),
      map.occupied_voxels(), result.dropped, map.store().bytes_used(), map.store().bytes_reserved(), out_path.c_str(),
      file.size(), nodes, map_digest(map), spec.width, spec.height, grid_counts.occupied, grid_counts.free);
  return result.dropped > 0 ? 3 : 0;
}
