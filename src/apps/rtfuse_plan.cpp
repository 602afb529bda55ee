// rtfuse-plan: plans on a saved map, the planner of the runtime on the
// map_server pair the mapper writes (issue 28):
//
//   rtfuse-plan --map MAP.yaml --pairs PAIRS.txt [--inflation R]
//
// Each line "sx sy gx gy" of PAIRS.txt is a start and a goal cell, indexed
// as nav_msgs/OccupancyGrid does (x to the right, y up from the PGM's bottom
// row). The map becomes a costmap (navigation/costmap.hpp): obstacles,
// cells within R metres of one closed to the robot's centre (inscribed),
// and with --decay D a band of D metres beyond where the cost falls off as
// costmap_2d's; unknown cells are closed unless --unknown free. With
// --inflation 0 and no decay the graph is the plain one: 8-connected over
// free cells, no diagonal step past an occupied corner, steps of 1 and
// sqrt(2).
//
// One line a pair (its status, cost in cells, length, time), then the JSON
// object: pairs, reached, cost_sum (the reached paths' costs, in cells),
// ms_median (over every plan; --repeat K plans each pair K times), the
// expansions and the failures by reason. Exit: 0 done (whatever was
// reached), 1 a file could not be read, 2 usage.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "apps/json_text.hpp"
#include "apps/map_server_map.hpp"
#include "apps/plan_pairs.hpp"
#include "navigation/costmap.hpp"
#include "navigation/grid_planner.hpp"

int main(int argc, char** argv) {
  using namespace rtfuse;
  rtfuse::apps::CommandLine cli{"rtfuse-plan: the grid planner on a saved map (map_server YAML + PGM)"};
  std::string map_path, pairs_path, unknown = "closed";
  double inflation = 0.0, decay = 0.0, scaling = 10.0, weight = 2.0;
  int repeat = 1;
  bool dijkstra = false;
  cli.option("--map", &map_path, "the map's YAML (map_server's format, as rtfused --map-out writes it)").required();
  cli.option("--pairs", &pairs_path, "start and goal cells, \"sx sy gx gy\" a line").required();
  cli.option("--inflation", &inflation, "the robot's inscribed radius, m: cells this near an obstacle are closed")
      .range(0.0, 10.0);
  cli.option("--decay", &decay, "a band this wide beyond --inflation where costs fall off (costmap_2d's), m")
      .range(0.0, 10.0);
  cli.option("--cost-scaling", &scaling, "costmap_2d's cost_scaling_factor in the band, 1/m")
      .range(0.0, 1000.0);
  cli.option("--cost-weight", &weight, "a step costs its length x (1 + weight x cost / 252)")
      .range(0.0, navigation::kMaxCostWeight);
  cli.option("--unknown", &unknown, "unknown cells: closed or free").one_of({"closed", "free"});
  cli.option("--repeat", &repeat, "plan each pair this many times; the JSON has the median time")
      .range(1, 1000);
  cli.flag("--dijkstra", &dijkstra, "Dijkstra instead of A* (the same costs, more cells expanded)");
  if (const auto exit = cli.parse(argc, argv)) return *exit;

  apps::OccupancyGridMap map;
  const std::string map_error = apps::load_map_server(map_path, &map);
  if (!map_error.empty()) {
    std::fprintf(stderr, "rtfuse-plan: %s\n", map_error.c_str());
    return 1;
  }
  std::vector<apps::PlanPair> pairs;
  try {
    pairs = apps::read_plan_pairs(pairs_path);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "rtfuse-plan: %s\n", e.what());
    return 1;
  }

  navigation::CostmapParams cp;
  cp.resolution_m = map.resolution;
  cp.inscribed_radius_m = inflation;
  cp.inflation_radius_m = inflation + decay;
  cp.cost_scaling_factor = scaling;
  cp.unknown = unknown == "free" ? navigation::UnknownCells::kFree : navigation::UnknownCells::kNoInformation;
  const std::string cost_error = navigation::check(cp);
  if (!cost_error.empty()) {
    std::fprintf(stderr, "rtfuse-plan: --inflation/--decay with a %g m map: %s\n", map.resolution,
                 cost_error.c_str());
    return 2;
  }
  std::unique_ptr<navigation::Costmap> costmap;
  std::unique_ptr<navigation::GridPlanner> planner;
  try {
    costmap.reset(new navigation::Costmap(map.width, map.height, cp));
    planner.reset(new navigation::GridPlanner(
        map.width, map.height, static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height)));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rtfuse-plan: %s: a %d x %d map: %s\n", map_path.c_str(), map.width, map.height, e.what());
    return 1;
  }
  costmap->set_grid(map.cells.data());
  navigation::PlannerParams pp;
  pp.cost_weight = weight;
  pp.mode = dijkstra ? navigation::SearchMode::kDijkstra : navigation::SearchMode::kAStar;

  std::vector<double> ms;
  ms.reserve(pairs.size() * static_cast<std::size_t>(repeat));
  std::map<std::string, int> failures;
  int reached = 0;
  double cost_sum = 0.0;
  std::size_t expansions = 0;
  for (const apps::PlanPair& pair : pairs) {
    navigation::PlanResult r;
    for (int k = 0; k < repeat; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      r = planner->plan(costmap->view(), {pair.sx, pair.sy}, {pair.gx, pair.gy}, pp);
      const auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    expansions += r.expansions;
    if (r.ok()) {
      ++reached;
      cost_sum += r.cost;
      std::printf("line %zu: (%d, %d) -> (%d, %d): cost %.12f cells, %zu cells, %zu expanded\n", pair.line, pair.sx,
                  pair.sy, pair.gx, pair.gy, r.cost, r.path_cells, r.expansions);
    } else {
      ++failures[navigation::to_string(r.status)];
      std::printf("line %zu: (%d, %d) -> (%d, %d): %s\n", pair.line, pair.sx, pair.sy, pair.gx, pair.gy,
                  navigation::to_string(r.status));
    }
  }
  std::sort(ms.begin(), ms.end());
  const double median = ms.empty() ? 0.0 : ms[ms.size() / 2];
  std::string failed = "{";
  for (const auto& [why, n] : failures) {
    if (failed.size() > 1) failed += ", ";
    failed += apps::json_string(why) + ": " + std::to_string(n);
  }
  failed += "}";
  std::printf(
      "{\"map\": %s, \"width\": %d, \"height\": %d, \"resolution\": %.9g, \"inflation\": %.9g, \"decay\": %.9g, "
      "\"search\": \"%s\", \"pairs\": %zu, \"reached\": %d, \"cost_sum\": %.9f, \"ms_median\": %.6f, "
      "\"expansions\": %zu, \"failures\": %s}\n",
      apps::json_string(map_path).c_str(), map.width, map.height, map.resolution, inflation, decay,
      dijkstra ? "dijkstra" : "astar", pairs.size(), reached, cost_sum, median, expansions, failed.c_str());
  return 0;
}
