// The mapping stages after the disparity (issue 27), for
// docs/performance.md; the insertion itself is measured against OctoMap in
// rtfuse_bench_octomap.
//
//   BM_MapInsertRoom       one scan of the room (40,000 rays, 6 m range,
//                          0.05 m) into a map already holding its earlier
//                          scans, the mapper's steady state: the stage that
//                          runs four rays at a time where the CPU has AVX2,
//                          one at a time on aarch64
//   BM_DisparityPoints     a VGA pair's half-resolution disparity (320 x 240,
//                          a slanted plane 1-6 m away) back-projected and
//                          carried into the map frame
//   BM_GridProjection/N    the 2-D grid, N x N cells at 0.05 m, from a map of
//                          a room's scans (0.4 M voxels)
//   BM_MapDigest/R         the digest of a map of R such rooms 16 m apart,
//                          from all of it
//   BM_ScanViews/R         the digest and a 400 x 400 grid of that map
//                          brought up to date after one more scan of the
//                          first room (MapDigest and ProjectedGrid:
//                          note_scan, refresh), what the mapper does at 1 Hz;
//                          with R = 1 the scan touches the whole map
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "mapping/disparity_points.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/map_digest.hpp"
#include "mapping/occupancy_map.hpp"
#include "support/alloc_counter.hpp"

namespace mapping_bench {

using namespace rtfuse;

void BM_DisparityPoints(benchmark::State& state) {
  const int w = 320, h = 240;
  std::vector<std::uint16_t> d(static_cast<std::size_t>(w) * h);
  const vision::StereoCameraModel camera{350.0, 320.0, 240.0, 0.12};
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const double z = 1.0 + 5.0 * (h - v) / h;  // nearer at the bottom
      d[static_cast<std::size_t>(v) * w + u] = static_cast<std::uint16_t>(std::lround(350.0 * 0.12 / z * 16.0));
    }
  geometry::RigidTransform mount;
  mount.translation = Eigen::Vector3d(0.2, 0.06, 0.3);
  std::vector<mapping::MapPoint> out(d.size());
  const vision::DisparityImage image{d.data(), w, h, w};
  std::size_t allocations = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    const auto c = mapping::disparity_points(image, 2, camera, mount, out.data(), out.size());
    benchmark::DoNotOptimize(c.points);
    allocations += scope.count();
  }
  state.counters["points"] = static_cast<double>(d.size());
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

// Scans of a round room 8 m across, 40,000 rays, from a sensor stepping
// along x.
std::vector<mapping::MapPoint> room_scan() {
  std::vector<mapping::MapPoint> scan;
  for (int i = 0; i < 4000; ++i) {
    const float a = 0.00157f * i;
    for (int k = 0; k < 10; ++k) scan.push_back({8.0f * std::cos(a), 8.0f * std::sin(a), 0.2f * k});
  }
  return scan;
}

mapping::OccupancyParams five_cm() {
  mapping::OccupancyParams p;
  p.resolution = 0.05;
  return p;
}

void BM_GridProjection(benchmark::State& state) {
  mapping::OccupancyMap map(five_cm(), mapping::capacity_for_bytes(std::size_t{128} << 20));
  const std::vector<mapping::MapPoint> scan = room_scan();
  for (int s = 0; s < 3; ++s) map.insert_scan(scan.data(), scan.size(), {0.5f * s, 0.0f, 0.4f}, 6.0);
  const int n = static_cast<int>(state.range(0));
  const mapping::GridSpec spec = mapping::grid_around(map.grid(), 0.0, 0.0, n, n, 0.1, 2.0);
  std::vector<std::int8_t> cells(spec.cells());
  std::size_t allocations = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    benchmark::DoNotOptimize(mapping::project_to_grid(map, spec, cells.data()).occupied);
    allocations += scope.count();
  }
  state.counters["voxels"] = static_cast<double>(map.known_voxels());
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

// R rooms 16 m apart along x, three scans each.
void map_rooms(mapping::OccupancyMap& map, int rooms) {
  std::vector<mapping::MapPoint> scan = room_scan();
  for (int r = 0; r < rooms; ++r) {
    for (int s = 0; s < 3; ++s) map.insert_scan(scan.data(), scan.size(), {16.0f * r + 0.5f * s, 0.0f, 0.4f}, 6.0);
    for (mapping::MapPoint& p : scan) p.x += 16.0f;
  }
}

void BM_MapDigest(benchmark::State& state) {
  mapping::OccupancyMap map(five_cm(), mapping::capacity_for_bytes(std::size_t{512} << 20));
  map_rooms(map, static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(mapping::map_digest(map));
  state.counters["voxels"] = static_cast<double>(map.known_voxels());
}

void BM_ScanViews(benchmark::State& state) {
  mapping::OccupancyMap map(five_cm(), mapping::capacity_for_bytes(std::size_t{512} << 20));
  map_rooms(map, static_cast<int>(state.range(0)));
  const std::vector<mapping::MapPoint> scan = room_scan();
  const mapping::GridSpec spec = mapping::grid_around(map.grid(), 0.0, 0.0, 400, 400, 0.1, 2.0);
  mapping::ProjectedGrid grid(map, spec);
  mapping::MapDigest digest(map);
  std::size_t allocations = 0;
  int s = 0;
  for (auto _ : state) {
    state.PauseTiming();
    map.insert_scan(scan.data(), scan.size(), {0.5f * (s++ % 4), 0.0f, 0.4f}, 6.0);
    state.ResumeTiming();
    rtfuse::test::AllocScope scope;
    digest.note_scan(map);
    grid.note_scan(map);
    benchmark::DoNotOptimize(digest.refresh(map));
    benchmark::DoNotOptimize(grid.refresh(map));
    allocations += scope.count();
  }
  state.counters["bricks"] = static_cast<double>(map.scan_brick_count());
  state.counters["voxels"] = static_cast<double>(map.known_voxels());
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

void BM_MapInsertRoom(benchmark::State& state) {
  mapping::OccupancyMap map(five_cm(), mapping::capacity_for_bytes(std::size_t{256} << 20));
  map_rooms(map, 1);
  const std::vector<mapping::MapPoint> scan = room_scan();
  std::size_t allocations = 0;
  int s = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    benchmark::DoNotOptimize(map.insert_scan(scan.data(), scan.size(), {0.5f * (s++ % 4), 0.0f, 0.4f}, 6.0));
    allocations += scope.count();
  }
  state.counters["rays"] = static_cast<double>(scan.size());
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

BENCHMARK(BM_MapInsertRoom)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DisparityPoints)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridProjection)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MapDigest)->Arg(1)->Arg(8)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanViews)->Arg(1)->Arg(8)->Unit(benchmark::kMillisecond);

}  // namespace mapping_bench
