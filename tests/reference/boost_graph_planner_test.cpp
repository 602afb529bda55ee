// The grid planner against Boost Graph (issue 28's optimality target): on
// random grids (obstacles, inscribed and unknown cells, random costs, both
// passability rules, weights from 0 to 20, random start and goal) our A*
// and Dijkstra costs equal boost::dijkstra_shortest_paths' distance to the
// goal to 1e-9 relative, "no route" exactly where Boost reaches no goal,
// and every path's steps are edges of Boost's graph summing to the cost.
// Then the benchmark's 400 x 400 costmaps and pairs, against both Boost's
// Dijkstra and its astar_search (the benchmark's opponent): the synthetic
// room and the obstacle course as the camera path mapped it on a
// simulated lap (tests/support/obstacle_course_map.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "navigation/grid_planner.hpp"
#include "reference/boost_grid_graph.hpp"
#include "support/obstacle_course_map.hpp"
#include "support/synthetic_costmap.hpp"

namespace boost_graph_planner_test {

using namespace rtfuse::navigation;
using rtfuse::test::BoostGridGraph;
using rtfuse::test::BoostVertex;
using rtfuse::test::kBoostUnreached;

constexpr double kRelative = 1e-9;

struct Grid {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> cost;
  CostView view() const { return CostView{cost.data(), width, height}; }
};

// Costs as a costmap has them: obstacles (some boxes), a cost falling off
// around them, scattered unknown cells, noise elsewhere.
Grid random_grid(std::mt19937& rng, int width, int height) {
  Grid g{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height, 0)};
  const unsigned obstacles = rng() % 45;
  const unsigned noise = rng() % 60;
  for (auto& c : g.cost) {
    const unsigned roll = rng() % 100;
    if (roll < obstacles) {
      c = rng() % 5 == 0 ? kCostInscribed : kCostLethal;
    } else if (rng() % 100 < 4) {
      c = kCostUnknown;
    } else if (rng() % 100 < noise) {
      c = static_cast<std::uint8_t>(rng() % 253);
    }
  }
  const unsigned boxes = rng() % 6;
  for (unsigned k = 0; k < boxes; ++k) {
    const int x0 = static_cast<int>(rng() % static_cast<unsigned>(width));
    const int y0 = static_cast<int>(rng() % static_cast<unsigned>(height));
    const int w = 1 + static_cast<int>(rng() % 12);
    const int h = 1 + static_cast<int>(rng() % 12);
    for (int y = y0; y < std::min(height, y0 + h); ++y) {
      for (int x = x0; x < std::min(width, x0 + w); ++x) g.cost[static_cast<std::size_t>(y) * width + x] = kCostLethal;
    }
  }
  return g;
}

bool passable(const Grid& g, const PlannerParams& p, GridCell c) {
  return p.passability.passable(g.view().at(c.x, c.y));
}

// The path's steps are edges of Boost's graph, their weights summing to
// the planner's cost.
void expect_path_in(const BoostGridGraph& bg, int width, const PlanResult& r) {
  double sum = 0.0;
  for (std::size_t i = 1; i < r.path_cells; ++i) {
    const auto u = static_cast<BoostVertex>(r.path[i - 1].y * width + r.path[i - 1].x);
    const auto v = static_cast<BoostVertex>(r.path[i].y * width + r.path[i].x);
    const auto edge = boost::edge(u, v, bg);
    ASSERT_TRUE(edge.second) << "step " << i << " is not an edge of Boost's graph";
    sum += bg[edge.first].weight;
  }
  EXPECT_NEAR(sum, r.cost, kRelative * r.cost);
}

TEST(BoostGraphReference, CostsEqualBoostsDijkstraOnRandomGrids) {
  std::mt19937 rng(2028);
  GridPlanner planner(80, 80, 80 * 80);
  const double weights[] = {0.0, 0.5, 1.0, 2.0, 5.0, 20.0};
  int compared = 0, unreachable = 0, refused = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 80);
    const int h = 1 + static_cast<int>(rng() % 80);
    const Grid g = random_grid(rng, w, h);
    PlannerParams p;
    p.cost_weight = weights[rng() % 6];
    p.passability.unknown_passable = rng() % 2 == 0;
    p.passability.lethal_from = rng() % 4 == 0 ? kCostLethal : kCostInscribed;
    const BoostGridGraph bg = rtfuse::test::boost_grid_graph(g.view(), p);
    const auto cell = [&rng, w, h] {
      const int x = static_cast<int>(rng() % static_cast<unsigned>(w));
      return GridCell{x, static_cast<int>(rng() % static_cast<unsigned>(h))};
    };
    // Several goals from one start: one Boost run gives all their distances.
    const GridCell start = cell();
    const std::vector<double> distance =
        rtfuse::test::boost_distances(bg, static_cast<BoostVertex>(start.y * w + start.x));
    for (int k = 0; k < 4; ++k) {
      const GridCell goal = cell();
      const double want = distance[static_cast<std::size_t>(goal.y * w + goal.x)];
      for (SearchMode mode : {SearchMode::kAStar, SearchMode::kDijkstra}) {
        p.mode = mode;
        const PlanResult r = planner.plan(g.view(), start, goal, p);
        if (!passable(g, p, start)) {
          ASSERT_EQ(r.status, PlanStatus::kStartBlocked);
          ++refused;
        } else if (!passable(g, p, goal)) {
          ASSERT_TRUE(r.status == PlanStatus::kGoalInObstacle || r.status == PlanStatus::kGoalUnknown);
          ++refused;
        } else if (want == kBoostUnreached) {
          ASSERT_EQ(r.status, PlanStatus::kNoRoute) << "trial " << trial << ": Boost reaches no goal";
          ++unreachable;
        } else {
          ASSERT_EQ(r.status, PlanStatus::kOk) << "trial " << trial << ": " << to_string(r.status);
          ASSERT_NEAR(r.cost, want, kRelative * want)
              << "trial " << trial << (mode == SearchMode::kAStar ? " A*" : " Dijkstra");
          expect_path_in(bg, w, r);
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 4000);
  EXPECT_GT(unreachable, 500);
  EXPECT_GT(refused, 1000);
  std::printf("compared %d plans, %d without a route, %d refused (start or goal not passable)\n", compared,
              unreachable, refused);
}

// Boost's A* (the benchmark's opponent) for every pair, its Dijkstra (the
// whole map each time) for one pair in `dijkstra_every`; our A* and
// Dijkstra equal to both, every path in Boost's graph. Returns the pairs
// reached.
int expect_boosts_costs(const rtfuse::test::SyntheticCostmap& map, std::size_t dijkstra_every) {
  const PlannerParams p;  // the defaults the benchmark plans with
  const BoostGridGraph bg = rtfuse::test::boost_grid_graph(map.view(), p);
  rtfuse::test::BoostAStar boost_astar(bg, map.width);
  GridPlanner planner(map.width, map.height, 4000);
  int reached = 0;
  for (std::size_t i = 0; i < map.starts.size(); ++i) {
    const GridCell s = map.starts[i], e = map.goals[i];
    const auto source = static_cast<BoostVertex>(s.y * map.width + s.x);
    const auto target = static_cast<BoostVertex>(e.y * map.width + e.x);
    const double want = boost_astar.plan(source, target);
    if (i % dijkstra_every == 0) {
      const double dijkstra = rtfuse::test::boost_distances(bg, source)[target];
      if (want == kBoostUnreached) {
        EXPECT_EQ(dijkstra, kBoostUnreached) << "pair " << i;
      } else {
        EXPECT_NEAR(dijkstra, want, kRelative * want) << "pair " << i;
      }
    }
    for (SearchMode mode : {SearchMode::kAStar, SearchMode::kDijkstra}) {
      PlannerParams q = p;
      q.mode = mode;
      const PlanResult r = planner.plan(map.view(), s, e, q);
      if (want == kBoostUnreached) {
        EXPECT_EQ(r.status, PlanStatus::kNoRoute) << "pair " << i;
        continue;
      }
      reached += mode == SearchMode::kAStar;
      EXPECT_TRUE(r.ok()) << "pair " << i << ": " << to_string(r.status);
      if (!r.ok()) continue;
      EXPECT_NEAR(r.cost, want, kRelative * want) << "pair " << i;
      expect_path_in(bg, map.width, r);
    }
  }
  return reached;
}

TEST(BoostGraphReference, TheBenchmarksCostmapGivesBoostsCostsToo) {
  const rtfuse::test::SyntheticCostmap map = rtfuse::test::synthetic_costmap();
  const int reached = expect_boosts_costs(map, 5);
  EXPECT_GT(reached, 80);
  std::printf("%d of %zu pairs reached\n", reached, map.starts.size());
}

// A map from a simulated drive: the obstacle course's lap mapped by the
// camera path (a keyframe a second), its 400 x 400 costmap, 100 pairs the
// helper found routes for (with our planner: Boost must agree).
TEST(BoostGraphReference, TheMappedObstacleCourseGivesBoostsCostsToo) {
  rtfuse::test::ObstacleCourseMapping course;
  ASSERT_EQ(course.error(), "");
  ASSERT_GT(course.drive(1.0, [](const rtfuse::geometry::RigidTransform&) {}), 40) << course.error();
  const rtfuse::test::SyntheticCostmap map = rtfuse::test::obstacle_course_costmap(course.map());
  ASSERT_EQ(map.starts.size(), 100u);
  std::size_t unknown = 0, blocked = 0;
  for (const std::uint8_t c : map.cost) {
    unknown += c == kCostUnknown;
    blocked += c == kCostLethal || c == kCostInscribed;
  }
  // What the camera saw is a part of the 20 m square, with obstacles in it.
  EXPECT_GT(unknown, map.cost.size() / 10);
  EXPECT_GT(blocked, 2000u);
  EXPECT_EQ(expect_boosts_costs(map, 2), 100);
  std::printf("obstacle course: %zu unknown cells, %zu lethal or inscribed of %zu\n", unknown, blocked,
              map.cost.size());
}

}  // namespace boost_graph_planner_test
