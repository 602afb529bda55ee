// The mapping stages after the disparity (issue 27), for
// docs/performance.md; the insertion itself is measured against OctoMap in
// rtfuse_bench_octomap.
//
//   BM_DisparityPoints     a VGA pair's half-resolution disparity (320 x 240,
//                          a slanted plane 1-6 m away) back-projected and
//                          carried into the map frame
//   BM_GridProjection/N    the 2-D grid, N x N cells at 0.05 m, from a map of
//                          a room's scans (0.4 M voxels)
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "mapping/disparity_points.hpp"
#include "mapping/grid_projection.hpp"
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

void BM_GridProjection(benchmark::State& state) {
  mapping::OccupancyParams p;
  p.resolution = 0.05;
  mapping::OccupancyMap map(p, mapping::capacity_for_bytes(std::size_t{128} << 20));
  std::vector<mapping::MapPoint> scan;
  for (int i = 0; i < 4000; ++i) {
    const float a = 0.00157f * i;
    for (int k = 0; k < 10; ++k) scan.push_back({8.0f * std::cos(a), 8.0f * std::sin(a), 0.2f * k});
  }
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

BENCHMARK(BM_DisparityPoints)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridProjection)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond);

}  // namespace mapping_bench
