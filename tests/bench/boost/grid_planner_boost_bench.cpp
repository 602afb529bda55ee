// The grid planner against Boost Graph's astar_search, side by side in one
// run (issue 28), on three 400 x 400 costmaps, 100 fixed start/goal pairs
// each: two synthetic (tests/support/synthetic_costmap.hpp), map 0 a room
// with four long inner walls with doorways (routes detour through them),
// map 1 the same room without them; and map 2 built from a simulated
// drive, the obstacle course as the camera path mapped it on a lap
// (tests/support/obstacle_course_map.hpp, a keyframe a second, some
// seconds to build before the first benchmark).
//
//   BM_GridPlanner/map/dijkstra   GridPlanner::plan, A* (0) or Dijkstra (1)
//   BM_BoostAStar/map             boost::astar_search on the same graph
//                                 (built once, outside the timing: Boost's
//                                 compressed sparse row graph,
//                                 tests/reference/boost_grid_graph.hpp), the
//                                 same heuristic, stopped at the goal as
//                                 Boost's examples do, its property maps
//                                 sized once
//   BM_SmoothPath/map             smooth_path over the 100 planned paths
//
// An iteration plans all 100 pairs, each timed on its own. Counters:
// median_ms and max_ms (per plan, over every plan of the run), expansions
// (ours, per plan), reached (pairs with a route) and allocs_per_iter
// (ours). Both sides' costs are checked equal to 1e-9 (the run stops with
// an error otherwise). Run them interleaved so the machine's drift falls
// on both (the command in docs/performance.md):
//   rtfuse_bench_boost --benchmark_enable_random_interleaving=true
//                      --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "navigation/grid_planner.hpp"
#include "navigation/path_smoother.hpp"
#include "reference/boost_grid_graph.hpp"
#include "support/alloc_counter.hpp"
#include "support/obstacle_course_map.hpp"
#include "support/synthetic_costmap.hpp"

namespace grid_planner_boost_bench {

using namespace rtfuse::navigation;
using Clock = std::chrono::steady_clock;

constexpr int kMaps = 3;

rtfuse::test::SyntheticCostmap mapped_course() {
  rtfuse::test::ObstacleCourseMapping course;
  if (course.drive(1.0, [](const rtfuse::geometry::RigidTransform&) {}) <= 0) return {};
  return rtfuse::test::obstacle_course_costmap(course.map());
}

// Map 0: the room with inner walls; 1: without; 2: the mapped course.
const rtfuse::test::SyntheticCostmap& costmap(std::int64_t map) {
  static const rtfuse::test::SyntheticCostmap maps[kMaps] = {
      rtfuse::test::synthetic_costmap(true), rtfuse::test::synthetic_costmap(false), mapped_course()};
  return maps[map];
}

const rtfuse::test::BoostGridGraph& boost_graph(std::int64_t map) {
  static const rtfuse::test::BoostGridGraph graphs[kMaps] = {
      rtfuse::test::boost_grid_graph(costmap(0).view(), PlannerParams{}),
      rtfuse::test::boost_grid_graph(costmap(1).view(), PlannerParams{}),
      rtfuse::test::boost_grid_graph(costmap(2).view(), PlannerParams{})};
  return graphs[map];
}

// Boost's A* costs, the reference both sides are checked against.
std::vector<double> boost_costs(std::int64_t map) {
  rtfuse::test::BoostAStar astar(boost_graph(map), costmap(map).width);
  std::vector<double> out;
  for (std::size_t i = 0; i < costmap(map).starts.size(); ++i) {
    const GridCell s = costmap(map).starts[i], e = costmap(map).goals[i];
    out.push_back(astar.plan(static_cast<rtfuse::test::BoostVertex>(s.y * costmap(map).width + s.x),
                             static_cast<rtfuse::test::BoostVertex>(e.y * costmap(map).width + e.x)));
  }
  return out;
}

const std::vector<double>& reference_costs(std::int64_t map) {
  static const std::vector<double> costs[kMaps] = {boost_costs(0), boost_costs(1), boost_costs(2)};
  return costs[map];
}

// A map that could not be built (the scenario or the renderer refused)
// has no pairs: its benchmarks say so instead of timing nothing.
bool usable(benchmark::State& state, std::int64_t map) {
  if (!costmap(map).starts.empty()) return true;
  state.SkipWithError("the costmap could not be built");
  return false;
}

bool same_cost(double ours, double reference) {
  if (reference == rtfuse::test::kBoostUnreached) return false;
  return std::abs(ours - reference) <= 1e-9 * reference;
}

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

void report_times(benchmark::State& state, std::vector<double>& times) {
  std::sort(times.begin(), times.end());
  const std::size_t n = times.size();
  const double median = n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
  state.counters["median_ms"] = median;
  state.counters["max_ms"] = times.back();
}

void BM_GridPlanner(benchmark::State& state) {
  if (!usable(state, state.range(0))) return;
  const rtfuse::test::SyntheticCostmap& map = costmap(state.range(0));
  const std::vector<double>& want = reference_costs(state.range(0));
  PlannerParams params;
  params.mode = state.range(1) == 0 ? SearchMode::kAStar : SearchMode::kDijkstra;
  GridPlanner planner(map.width, map.height, 4000);
  const std::size_t pairs = map.starts.size();
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(state.max_iterations) * pairs);
  std::size_t allocations = 0, expansions = 0, reached = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    for (std::size_t i = 0; i < pairs; ++i) {
      const Clock::time_point t0 = Clock::now();
      const PlanResult r = planner.plan(map.view(), map.starts[i], map.goals[i], params);
      times.push_back(ms_since(t0));
      expansions += r.expansions;
      if (r.ok() != (want[i] != rtfuse::test::kBoostUnreached) || (r.ok() && !same_cost(r.cost, want[i]))) {
        state.SkipWithError("a cost differs from Boost's");
        return;
      }
      reached += r.ok();
    }
    allocations += scope.count();
  }
  report_times(state, times);
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["expansions"] = static_cast<double>(expansions) / (iterations * static_cast<double>(pairs));
  state.counters["reached"] = static_cast<double>(reached) / iterations;
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / iterations;
}

void BM_BoostAStar(benchmark::State& state) {
  if (!usable(state, state.range(0))) return;
  const rtfuse::test::SyntheticCostmap& map = costmap(state.range(0));
  const std::vector<double>& want = reference_costs(state.range(0));
  rtfuse::test::BoostAStar astar(boost_graph(state.range(0)), map.width);
  const std::size_t pairs = map.starts.size();
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(state.max_iterations) * pairs);
  std::size_t allocations = 0, reached = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    for (std::size_t i = 0; i < pairs; ++i) {
      const GridCell s = map.starts[i], e = map.goals[i];
      const Clock::time_point t0 = Clock::now();
      const double cost = astar.plan(static_cast<rtfuse::test::BoostVertex>(s.y * map.width + s.x),
                                     static_cast<rtfuse::test::BoostVertex>(e.y * map.width + e.x));
      times.push_back(ms_since(t0));
      if (cost != want[i]) {
        state.SkipWithError("Boost's A* gave another cost than before");
        return;
      }
      reached += cost != rtfuse::test::kBoostUnreached;
    }
    allocations += scope.count();
  }
  report_times(state, times);
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["reached"] = static_cast<double>(reached) / iterations;
  // Not allocs_per_iter: Boost's heap is its own, made per search.
  state.counters["boost_allocs_per_plan"] = static_cast<double>(allocations) / (iterations * static_cast<double>(pairs));
}

void BM_SmoothPath(benchmark::State& state) {
  if (!usable(state, state.range(0))) return;
  const rtfuse::test::SyntheticCostmap& map = costmap(state.range(0));
  const PlannerParams params;
  GridPlanner planner(map.width, map.height, 4000);
  std::vector<std::vector<GridCell>> paths;
  for (std::size_t i = 0; i < map.starts.size(); ++i) {
    const PlanResult r = planner.plan(map.view(), map.starts[i], map.goals[i], params);
    if (r.ok()) paths.emplace_back(r.path, r.path + r.path_cells);
  }
  std::vector<GridCell> out(4000);
  std::size_t cells_in = 0, cells_out = 0, allocations = 0;
  for (auto _ : state) {
    rtfuse::test::AllocScope scope;
    for (const auto& path : paths) {
      cells_in += path.size();
      cells_out += smooth_path(map.view(), params.passability, path.data(), path.size(), out.data());
    }
    allocations += scope.count();
  }
  const auto plans = static_cast<double>(state.iterations() * paths.size());
  state.counters["ms_per_path"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(paths.size()) / 1000.0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["waypoints_in"] = static_cast<double>(cells_in) / plans;
  state.counters["waypoints_out"] = static_cast<double>(cells_out) / plans;
  state.counters["allocs_per_iter"] = static_cast<double>(allocations) / static_cast<double>(state.iterations());
}

BENCHMARK(BM_GridPlanner)
    ->ArgNames({"map", "dijkstra"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(5);
BENCHMARK(BM_BoostAStar)->ArgName("map")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_SmoothPath)->ArgName("map")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(20);

}  // namespace grid_planner_boost_bench
