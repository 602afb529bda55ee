// The costmap of issue 28 (navigation/costmap.hpp) on a 400 x 400 grid
// (20 m at 0.05 m) with a course of boxes and pillars, a robot of 0.2 m
// inscribed and 0.55 m inflation radius:
//
//   BM_CostmapSetGrid      every cost anew from the grid
//   BM_CostmapUpdate/N     after N cells in one place changed (a patch of
//                          the map the camera just saw): update() compares
//                          the grids and redoes the tiles near the change;
//                          per_changed_cell is its time over N
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "navigation/costmap.hpp"
#include "support/alloc_counter.hpp"

namespace costmap_bench {

using namespace rtfuse::navigation;

constexpr int kSide = 400;

std::vector<std::int8_t> course() {
  std::vector<std::int8_t> grid(static_cast<std::size_t>(kSide) * kSide, 0);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> at(0, kSide - 30), size(3, 30);
  for (int box = 0; box < 40; ++box) {
    const int x0 = at(rng), y0 = at(rng), w = size(rng), h = size(rng);
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) grid[static_cast<std::size_t>(y) * kSide + x] = 100;
  }
  for (int i = 0; i < kSide * 40; ++i) grid[static_cast<std::size_t>(at(rng)) * kSide + at(rng)] = -1;  // unseen
  return grid;
}

CostmapParams robot() {
  CostmapParams p;
  p.resolution_m = 0.05;
  p.inscribed_radius_m = 0.2;
  p.inflation_radius_m = 0.55;
  return p;
}

void BM_CostmapSetGrid(benchmark::State& state) {
  const std::vector<std::int8_t> grid = course();
  Costmap map(kSide, kSide, robot());
  std::size_t allocations = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    map.set_grid(grid.data());
    allocations += scope.count();
  }
  benchmark::DoNotOptimize(map.cost(200, 200));
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

void BM_CostmapUpdate(benchmark::State& state) {
  std::vector<std::int8_t> grid = course();
  Costmap map(kSide, kSide, robot());
  map.set_grid(grid.data());
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> place(20, kSide - 60);
  std::size_t allocations = 0, changed = 0, tiles = 0;
  for (auto _ : state) {
    state.PauseTiming();
    // n cells of a patch become obstacles (or free again): a wall seen.
    const int x0 = place(rng), y0 = place(rng);
    for (int i = 0; i < n; ++i) {
      std::int8_t& c = grid[static_cast<std::size_t>(y0 + i / 40) * kSide + x0 + i % 40];
      c = c == 100 ? 0 : 100;
    }
    state.ResumeTiming();
    rtfuse::test::AllocScope scope;
    changed += map.update(grid.data());
    allocations += scope.count();
    tiles += map.tiles_redone();
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["changed"] = static_cast<double>(changed) / iterations;
  state.counters["tiles"] = static_cast<double>(tiles) / iterations;
  // Seconds of update per changed cell (the time over the cells changed).
  state.counters["per_changed_cell"] =
      benchmark::Counter(static_cast<double>(changed), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / iterations;
}

BENCHMARK(BM_CostmapSetGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CostmapUpdate)->Arg(1)->Arg(40)->Arg(400)->Unit(benchmark::kMicrosecond);

}  // namespace costmap_bench
