// rtfuse-map: builds an occupancy map offline (OctoMap's semantics, the
// runtime's map) and writes it as OctoMap's .bt, and on request the 2-D grid
// as map_server's PGM + YAML and a picture. Two sources:
//
//   --cloud SCAN.xyz [--origin X,Y,Z]   one point cloud (x y z a line,
//                                       OctoMap's scan.dat) seen from one
//                                       origin; --repeat K inserts it K times
//                                       into an emptied map for a median time
//   --kitti DIR [--poses POSES.txt]     the rectified pairs of a KITTI-layout
//                                       folder: each frame's dense disparity
//                                       placed with its pose (the ground
//                                       truth, or e.g. rtfuse-vo's --out),
//                                       in a z-up frame (x forward, y left)
//                                       with the first camera at the origin
//   --bt MAP.bt                         a map OctoMap (or this tool) wrote:
//                                       read, then written out again and
//                                       projected like the others
//
// The last stdout line is a JSON object: points, times, known and occupied
// voxels, memory_bytes (the map's bytes in use, comparable with OctoMap's
// memoryUsage()) and the pool's, the file, the grid and the map's digest.
// Exit: 0 done, 1 a file could not be read or written, 2 usage, 3 the pool
// filled (the map is incomplete; the message says what to raise).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "apps/kitti_sequence.hpp"
#include "apps/map_figure.hpp"
#include "apps/point_cloud_file.hpp"
#include "apps/stereo_clouds.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/map_digest.hpp"
#include "mapping/map_server_files.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/octomap_binary_reader.hpp"
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

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// KITTI's camera frame (x right, y down, z forward) turned z-up: x forward,
// y left, z up, as a ground robot's map is.
Eigen::Matrix4d z_up_of_optical() {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return t;
}

struct Scan {
  MapPoint origin;
  std::vector<MapPoint> points;
};

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-map: an occupancy map (OctoMap's semantics) built offline, written as .bt"};
  std::string cloud_path, origin_text = "0,0,0", kitti_dir, poses_path, bt_path, out_path, grid_prefix, png_path;
  double resolution = 0.05, max_range = -1.0, z_min = -0.5, z_max = 2.0;
  int repeat = 1, first = 0, last = -1, every = 1, disparities = 96, downscale = 2;
  std::uint64_t pool_mib = 512;
  auto cloud_opt =
      cli.option("--cloud", &cloud_path, "point cloud, one \"x y z\" (metres) a line, as OctoMap's scan.dat");
  cli.option("--origin", &origin_text, "--cloud: the sensor's position X,Y,Z in the cloud's frame (metres)");
  cli.option("--repeat", &repeat, "--cloud: insert it this many times into an emptied map; ms_median over them")
      .range(1, 1000);
  auto kitti_opt = cli.option("--kitti", &kitti_dir,
                                   "KITTI-layout folder: image_l/ image_r/ (or image_0/ image_1/), calib.txt, "
                                   "poses.txt");
  cli.option("--poses", &poses_path, "--kitti: the left camera's poses, KITTI format (default: its poses.txt)");
  cli.option("--first", &first, "--kitti: the first frame").non_negative();
  cli.option("--last", &last, "--kitti: the last frame (default: the last with a pose)");
  cli.option("--every", &every, "--kitti: every n-th frame (keyframes)").range(1, 100000);
  cli.option("--disparities", &disparities, "--kitti: disparities searched (a multiple of 16 x downscale)");
  cli.option("--downscale", &downscale, "--kitti: 1 full resolution, 2 half (the live default)");
  auto bt_opt = cli.option("--bt", &bt_path, "an OctoMap binary tree (.bt): read, rewritten, projected");
  cloud_opt.excludes(kitti_opt);
  bt_opt.excludes(cloud_opt).excludes(kitti_opt);
  cli.option("--resolution", &resolution, "voxel edge (metres)");
  cli.option("--max-range", &max_range,
                 "rays longer than this free up to it and mark nothing (metres; negative: no limit)");
  cli.option("--pool-mib", &pool_mib, "memory reserved for the map (MiB); a full pool drops updates, counted")
      .range(1, 1 << 20);
  cli.option("-o,--out", &out_path, "the map as OctoMap's binary tree (.bt)").required();
  cli.option("--grid", &grid_prefix, "also write the 2-D grid as map_server's PREFIX.pgm and PREFIX.yaml");
  cli.option("--png", &png_path, "also draw the 2-D grid, the sensor's path, a legend and the figures");
  cli.option("--z-min", &z_min, "the grid's lowest voxel centres (metres)");
  cli.option("--z-max", &z_max, "the grid's highest voxel centres (metres)");
  if (const auto exit = cli.parse(argc, argv)) return *exit;
  if (cloud_path.empty() && kitti_dir.empty() && bt_path.empty()) {
    return cli.usage_error("--cloud, --kitti or --bt is required");
  }
  std::vector<std::uint8_t> bt_bytes;
  if (!bt_path.empty()) {
    std::ifstream in(bt_path, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "rtfuse-map: %s: cannot open: %s\n", bt_path.c_str(), std::strerror(errno));
      return 1;
    }
    bt_bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    OctomapBinaryHeader header;
    std::string error;
    if (!read_octomap_binary_header(bt_bytes.data(), bt_bytes.size(), bt_path, &header, &error)) {
      std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
      return 1;
    }
    resolution = header.resolution;  // the file's
  }
  OccupancyParams params;
  params.resolution = resolution;
  if (const std::string fault = check(params); !fault.empty()) {
    std::fprintf(stderr, "rtfuse-map: --resolution: %s\n", fault.c_str());
    return 2;
  }
  if (!(z_min <= z_max)) {
    std::fprintf(stderr, "rtfuse-map: --z-min %g is above --z-max %g\n", z_min, z_max);
    return 2;
  }

  // --- the scans ---------------------------------------------------------------
  std::vector<Scan> scans;
  std::vector<double> disparity_ms;
  std::vector<rtfuse::apps::DataPoint> path;
  std::string source;
  if (!bt_path.empty()) {
    source = bt_path;
  } else if (!cloud_path.empty()) {
    Scan scan;
    if (!parse_origin(origin_text, scan.origin)) {
      std::fprintf(stderr, "rtfuse-map: --origin \"%s\": expected three finite numbers X,Y,Z\n", origin_text.c_str());
      return 2;
    }
    try {
      scan.points = rtfuse::apps::read_xyz_cloud(cloud_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rtfuse-map: %s\n", e.what());
      return 1;
    }
    if (scan.points.empty()) {
      std::fprintf(stderr, "rtfuse-map: %s: no points\n", cloud_path.c_str());
      return 1;
    }
    path.push_back({scan.origin.x, scan.origin.y});
    scans.push_back(std::move(scan));
    source = cloud_path;
  } else {
    rtfuse::apps::KittiSequence seq;
    std::string error;
    if (!rtfuse::apps::open_kitti_sequence(kitti_dir, &seq, &error)) {
      std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
      return 1;
    }
    std::vector<Eigen::Matrix4d> poses = seq.ground_truth;
    if (!poses_path.empty()) {
      std::ifstream in(poses_path);
      std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (!in.good() && !in.eof()) {
        std::fprintf(stderr, "rtfuse-map: %s: cannot read: %s\n", poses_path.c_str(), std::strerror(errno));
        return 1;
      }
      if (!rtfuse::apps::parse_kitti_poses(text, poses_path, &poses, &error)) {
        std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
        return 1;
      }
    }
    if (poses.empty()) {
      std::fprintf(stderr, "rtfuse-map: %s has no poses.txt; give the camera's poses with --poses\n",
                   kitti_dir.c_str());
      return 2;
    }
    const int end = std::min<int>(static_cast<int>(std::min(poses.size(), seq.left.size())) - 1,
                                  last < 0 ? 1 << 30 : last);
    std::vector<int> frames;
    for (int k = first; k <= end; k += every) frames.push_back(k);
    if (frames.empty()) {
      std::fprintf(stderr, "rtfuse-map: no frame from %d to %d\n", first, end);
      return 2;
    }
    const Eigen::Matrix4d z_up = z_up_of_optical();
    for (Eigen::Matrix4d& p : poses) p = z_up * p;
    rtfuse::vision::DisparityParams dp;
    dp.disparities = disparities;
    dp.downscale = downscale;
    std::vector<rtfuse::apps::StereoCloud> clouds;
    if (!rtfuse::apps::stereo_clouds(seq, poses, frames, dp, &clouds, &error)) {
      std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
      return error.rfind("disparity:", 0) == 0 ? 2 : 1;
    }
    for (auto& c : clouds) {
      disparity_ms.push_back(c.disparity_ms);
      path.push_back({c.origin.x, c.origin.y});
      scans.push_back(Scan{c.origin, std::move(c.points)});
    }
    source = kitti_dir;
  }

  // --- the map -------------------------------------------------------------------
  const BrickCapacity capacity = capacity_for_bytes(pool_mib << 20);
  OccupancyMap map(params, capacity);
  std::vector<double> insert_ms;
  ScanResult total;
  std::size_t points = 0;
  if (!bt_bytes.empty()) {
    std::string error;
    const auto t0 = std::chrono::steady_clock::now();
    if (!read_octomap_binary(bt_bytes.data(), bt_bytes.size(), bt_path, map, &error)) {
      std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
      return error.find("cannot hold") != std::string::npos ? 3 : 1;
    }
    insert_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  for (int k = 0; k < (cloud_path.empty() ? 1 : repeat) && bt_bytes.empty(); ++k) {
    map.clear();
    total = ScanResult{};
    points = 0;
    for (const Scan& scan : scans) {
      const auto t0 = std::chrono::steady_clock::now();
      const ScanResult r = map.insert_scan(scan.points.data(), scan.points.size(), scan.origin, max_range);
      const auto t1 = std::chrono::steady_clock::now();
      insert_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      points += scan.points.size();
      total.hits += r.hits;
      total.frees += r.frees;
      total.beyond_range += r.beyond_range;
      total.outside += r.outside;
      total.rejected += r.rejected;
      total.dropped += r.dropped;
    }
  }

  OctomapBinaryWriter writer(capacity.bricks);
  std::vector<std::uint8_t> file;
  const std::size_t nodes = writer.write(map, file);
  if (!write_file(out_path, file.data(), file.size())) return 1;

  ProjectionCounts grid_counts;
  GridSpec spec;
  std::vector<std::int8_t> cells;
  if (!grid_prefix.empty() || !png_path.empty()) {
    spec = grid_of_known(map, z_min, z_max);
    cells.resize(spec.cells());
    grid_counts = project_to_grid(map, spec, cells.data());
  }
  const double ox = grid_origin_x(map.grid(), spec), oy = grid_origin_y(map.grid(), spec);
  if (!grid_prefix.empty()) {
    const std::vector<std::uint8_t> pgm = map_server_pgm(cells.data(), spec.width, spec.height);
    const std::string image = grid_prefix + ".pgm";
    const std::string yaml = map_server_yaml(image.substr(image.find_last_of('/') + 1), resolution, ox, oy);
    if (!write_file(image, pgm.data(), pgm.size()) ||
        !write_file(grid_prefix + ".yaml", yaml.data(), yaml.size())) {
      return 1;
    }
  }
  const double insert_median = median(insert_ms), disparity_median = median(disparity_ms);
  if (!png_path.empty()) {
    char line[160];
    rtfuse::apps::MapFigure figure;
    figure.title = "rtfuse-map: " + source;
    figure.cells = cells.data();
    figure.width = spec.width;
    figure.height = spec.height;
    figure.resolution = resolution;
    figure.origin_x = ox;
    figure.origin_y = oy;
    figure.path = path;
    figure.figures.push_back("# the map");
    if (bt_bytes.empty()) {
      std::snprintf(line, sizeof line, "scans       %zu (%zu points)", scans.size(), points);
    } else {
      std::snprintf(line, sizeof line, "read        %zu bytes of .bt", bt_bytes.size());
    }
    figure.figures.push_back(line);
    char range[32] = "unlimited";
    if (max_range >= 0) std::snprintf(range, sizeof range, "%.1f m", max_range);
    std::snprintf(line, sizeof line, "voxels      %.2f cm, range %s", resolution * 100.0, range);
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "known       %" PRIu64, map.known_voxels());
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "occupied    %" PRIu64, map.occupied_voxels());
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "memory      %.2f MB", map.store().bytes_used() / 1e6);
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, bt_bytes.empty() ? "insert      %.1f ms/scan median" : "load        %.1f ms",
                  insert_median);
    figure.figures.push_back(line);
    if (!disparity_ms.empty()) {
      std::snprintf(line, sizeof line, "disparity   %.1f ms/frame median", disparity_median);
      figure.figures.push_back(line);
    }
    figure.figures.push_back("");
    figure.figures.push_back("# the grid");
    std::snprintf(line, sizeof line, "heights     %.2f to %.2f m", z_min, z_max);
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "cells       %d x %d", spec.width, spec.height);
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "occupied    %zu", grid_counts.occupied);
    figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "free        %zu", grid_counts.free);
    figure.figures.push_back(line);
    std::string error;
    if (!rtfuse::apps::write_map_png(figure, png_path, &error)) {
      std::fprintf(stderr, "rtfuse-map: %s\n", error.c_str());
      return 1;
    }
  }
  if (total.dropped > 0) {
    std::fprintf(stderr,
                 "rtfuse-map: the pool (%zu MiB) is full: %u voxel updates dropped, the map is incomplete; "
                 "raise --pool-mib\n",
                 pool_mib, total.dropped);
  }
  if (total.rejected > 0) std::fprintf(stderr, "rtfuse-map: %u points not finite, skipped\n", total.rejected);

  std::printf(
      "{\"mode\": \"%s\", \"source\": \"%s\", \"scans\": %zu, \"points\": %zu, \"resolution\": %.9g, "
      "\"max_range\": %.9g, \"repeat\": %d, \"ms_median\": %.3f, \"disparity_ms_median\": %.3f, "
      "\"hits\": %u, \"frees\": %u, \"beyond_range\": %u, \"outside\": %u, \"rejected\": %u, "
      "\"known_voxels\": %" PRIu64 ", \"occupied_voxels\": %" PRIu64 ", \"dropped_updates\": %u, "
      "\"memory_bytes\": %zu, \"pool_bytes\": %zu, \"bt\": \"%s\", \"bt_bytes\": %zu, \"bt_nodes\": %zu, "
      "\"digest\": \"%016" PRIx64 "\", \"grid_width\": %d, \"grid_height\": %d, \"grid_occupied\": %zu, "
      "\"grid_free\": %zu}\n",
      !bt_path.empty() ? "bt" : cloud_path.empty() ? "kitti" : "cloud", source.c_str(), scans.size(), points, resolution, max_range,
      cloud_path.empty() ? 1 : repeat, insert_median, disparity_median, total.hits, total.frees, total.beyond_range,
      total.outside, total.rejected, map.known_voxels(), map.occupied_voxels(), total.dropped,
      map.store().bytes_used(), map.store().bytes_reserved(), out_path.c_str(), file.size(), nodes, map_digest(map),
      spec.width, spec.height, grid_counts.occupied, grid_counts.free);
  return total.dropped > 0 ? 3 : 0;
}
