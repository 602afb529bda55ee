// The occupancy map against OctoMap, side by side in one run (issue 27):
//
//   BM_OctomapInsert/R/M   OcTree(R mm)::insertPointCloud(scan.dat, origin,
//                          M m or unlimited (0), lazy_eval = false,
//                          discretize = false) into a fresh tree
//   BM_MapInsert/R/M       OccupancyMap::insert_scan of the same cloud into a
//                          cleared map (same result: tests/reference)
//   BM_OctomapWriteBinary/R, BM_MapWriteBinary/R
//                          the .bt file of the unlimited scan's map
//
// Counters: voxels (known after the scan), memory_bytes (OctoMap's
// memoryUsage(), the map's bytes in use) and allocs_per_iter for the map.
// Run them interleaved so the machine's drift falls on both (tools/bench.sh
// octomap, or the command in docs/performance.md):
//   rtfuse_bench_octomap --benchmark_enable_random_interleaving=true
//                        --benchmark_repetitions=5
// One thread each: Debian's OctoMap is built without OpenMP.
#include <benchmark/benchmark.h>

#include <memory>
#include <sstream>
#include <vector>

#include "mapping/octomap_binary.hpp"
#include "reference/octomap_reference.hpp"
#include "support/alloc_counter.hpp"

namespace octomap_insert_bench {

using namespace rtfuse::mapping;

constexpr BrickCapacity kPool{200000, 400000};

const std::vector<MapPoint>& scan() {
  static const std::vector<MapPoint> points = rtfuse::test::read_octomap_scan(RTFUSE_SHARED_DATA);
  return points;
}
const octomap::Pointcloud& octomap_scan() {
  static const octomap::Pointcloud cloud = rtfuse::test::to_octomap(scan());
  return cloud;
}

double resolution_of(const benchmark::State& state) { return static_cast<double>(state.range(0)) / 1000.0; }
double range_of(const benchmark::State& state) { return state.range(1) == 0 ? -1.0 : static_cast<double>(state.range(1)); }

OccupancyParams params(double resolution) {
  OccupancyParams p;
  p.resolution = resolution;
  return p;
}

void BM_OctomapInsert(benchmark::State& state) {
  const octomap::Pointcloud& cloud = octomap_scan();
  std::size_t memory = 0, leaves = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto tree = std::make_unique<octomap::OcTree>(resolution_of(state));
    state.ResumeTiming();
    tree->insertPointCloud(cloud, octomap::point3d(0, 0, 0), range_of(state), false, false);
    state.PauseTiming();
    memory = tree->memoryUsage();
    leaves = tree->getNumLeafNodes();
    tree.reset();
    state.ResumeTiming();
  }
  state.counters["memory_bytes"] = static_cast<double>(memory);
  state.counters["leaves"] = static_cast<double>(leaves);
}

void BM_MapInsert(benchmark::State& state) {
  const std::vector<MapPoint>& cloud = scan();
  OccupancyMap map(params(resolution_of(state)), kPool);
  map.insert_scan(cloud.data(), cloud.size(), {0, 0, 0}, range_of(state));  // the pool's pages, touched once
  std::size_t allocations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    map.clear();
    rtfuse::test::AllocScope scope;
    state.ResumeTiming();
    map.insert_scan(cloud.data(), cloud.size(), {0, 0, 0}, range_of(state));
    state.PauseTiming();
    allocations += scope.count();
    state.ResumeTiming();
  }
  state.counters["memory_bytes"] = static_cast<double>(map.store().bytes_used());
  state.counters["voxels"] = static_cast<double>(map.known_voxels());
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

void BM_OctomapWriteBinary(benchmark::State& state) {
  octomap::OcTree tree(resolution_of(state));
  tree.insertPointCloud(octomap_scan(), octomap::point3d(0, 0, 0), -1.0, false, false);
  std::size_t bytes = 0;
  for (auto _ : state) {
    std::ostringstream out;
    tree.writeBinary(out);
    bytes = out.str().size();
  }
  state.counters["file_bytes"] = static_cast<double>(bytes);
}

void BM_MapWriteBinary(benchmark::State& state) {
  OccupancyMap map(params(resolution_of(state)), kPool);
  map.insert_scan(scan().data(), scan().size(), {0, 0, 0}, -1.0);
  OctomapBinaryWriter writer(kPool.bricks);
  std::vector<std::uint8_t> out;
  for (auto _ : state) writer.write(map, out);
  state.counters["file_bytes"] = static_cast<double>(out.size());
}

// R in mm, M in m (0: no limit): the two resolutions, each with and
// without a 10 m range.
void Cases(benchmark::internal::Benchmark* b) {
  b->Args({100, 0})->Args({100, 10})->Args({50, 0})->Args({50, 10});
}

BENCHMARK(BM_OctomapInsert)->Apply(Cases)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_MapInsert)->Apply(Cases)->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK(BM_OctomapWriteBinary)->Arg(100)->Arg(50)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_MapWriteBinary)->Arg(100)->Arg(50)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace octomap_insert_bench
