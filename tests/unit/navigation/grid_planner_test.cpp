// The grid planner: optimal costs on hand-made grids whose answer is known
// (an open grid, a wall with a gap, a maze, corners, a cheap detour), every
// reason a plan is refused, unknown cells both ways, A* against Dijkstra
// and every path checked step by step on random grids, the same paths on
// every run and architecture (a pinned digest), and no allocation.
#include "navigation/grid_planner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/alloc_counter.hpp"

namespace grid_planner_test {

using namespace rtfuse::navigation;

struct Grid {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> cost;

  CostView view() const { return CostView{cost.data(), width, height}; }
  std::uint8_t& at(int x, int y) { return cost[static_cast<std::size_t>(y) * width + x]; }
};

Grid filled(int width, int height, std::uint8_t value) {
  return Grid{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height, value)};
}

// A picture of a grid, its first line the highest row (as the PGM a map is
// saved as): '.' free, '#' lethal, 'i' inscribed, '?' unknown, 'c' cost 126.
Grid picture(const std::vector<std::string>& rows) {
  Grid g = filled(static_cast<int>(rows[0].size()), static_cast<int>(rows.size()), 0);
  for (int r = 0; r < g.height; ++r) {
    const int y = g.height - 1 - r;
    for (int x = 0; x < g.width; ++x) {
      const char ch = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(x)];
      g.at(x, y) = ch == '#' ? 254 : ch == 'i' ? 253 : ch == '?' ? 255 : ch == 'c' ? 126 : 0;
    }
  }
  return g;
}

PlannerParams params(double weight, SearchMode mode = SearchMode::kAStar) {
  PlannerParams p;
  p.cost_weight = weight;
  p.mode = mode;
  return p;
}

double octile(int dx, int dy) {
  const int lo = std::min(std::abs(dx), std::abs(dy));
  const int hi = std::max(std::abs(dx), std::abs(dy));
  return (hi - lo) + std::sqrt(2.0) * lo;
}

// The path is a walk of 8-neighbour steps over passable cells from start to
// goal, no diagonal past a blocked corner, and its cost is the reported
// one: bit for bit as the planner sums (straight and diagonal factors
// apart), and to rounding as the plain sum of the step costs.
void expect_valid_path(const Grid& g, const PlanResult& r, GridCell start, GridCell goal, const PlannerParams& p) {
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  ASSERT_GE(r.path_cells, 1u);
  EXPECT_EQ(r.path[0], start);
  EXPECT_EQ(r.path[r.path_cells - 1], goal);
  const CostView v = g.view();
  const auto passable = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < g.width && y < g.height && p.passability.passable(v.at(x, y));
  };
  double straight = 0.0, diagonal = 0.0, sum = 0.0;
  for (std::size_t i = 0; i < r.path_cells; ++i) {
    const GridCell c = r.path[i];
    ASSERT_TRUE(passable(c.x, c.y)) << "cell " << i << " (" << c.x << ", " << c.y << ")";
    if (i == 0) continue;
    const GridCell b = r.path[i - 1];
    const int dx = c.x - b.x, dy = c.y - b.y;
    ASSERT_TRUE(std::abs(dx) <= 1 && std::abs(dy) <= 1 && (dx != 0 || dy != 0)) << "step " << i;
    const double factor = step_factor(v.at(c.x, c.y), p.cost_weight);
    if (dx != 0 && dy != 0) {
      ASSERT_TRUE(passable(b.x + dx, b.y) && passable(b.x, b.y + dy)) << "corner cut at step " << i;
      diagonal = diagonal + factor;
      sum = sum + std::sqrt(2.0) * factor;
    } else {
      straight = straight + factor;
      sum = sum + factor;
    }
  }
  EXPECT_EQ(straight + std::sqrt(2.0) * diagonal, r.cost);
  EXPECT_NEAR(sum, r.cost, 1e-12 * r.cost);
}

TEST(GridPlanner, AnOpenGridCostsTheOctileDistance) {
  const Grid g = filled(30, 20, 0);
  GridPlanner planner(30, 20, 100);
  const GridCell pairs[][2] = {
      {{0, 0}, {29, 19}}, {{3, 4}, {20, 4}}, {{5, 17}, {5, 2}}, {{28, 1}, {1, 7}}, {{7, 7}, {7, 7}}};
  for (const auto& pair : pairs) {
    for (SearchMode mode : {SearchMode::kAStar, SearchMode::kDijkstra}) {
      for (double weight : {0.0, 2.0}) {
        const PlannerParams p = params(weight, mode);
        const PlanResult r = planner.plan(g.view(), pair[0], pair[1], p);
        const int dx = pair[1].x - pair[0].x, dy = pair[1].y - pair[0].y;
        EXPECT_NEAR(r.cost, octile(dx, dy), 1e-12);
        EXPECT_EQ(r.path_cells, static_cast<std::size_t>(std::max(std::abs(dx), std::abs(dy))) + 1);
        expect_valid_path(g, r, pair[0], pair[1], p);
      }
    }
  }
  // On an open grid, A* goes straight for the goal: one expansion a step
  // (the goal itself is never expanded).
  const PlanResult r = planner.plan(g.view(), {0, 0}, {29, 19}, params(2.0));
  EXPECT_EQ(r.expansions, 29u);
  EXPECT_EQ(planner.plan(g.view(), {4, 4}, {4, 4}, params(2.0)).expansions, 0u);
  EXPECT_GT(planner.plan(g.view(), {0, 0}, {29, 19}, params(2.0, SearchMode::kDijkstra)).expansions, 500u);
}

TEST(GridPlanner, AWallWithAGapIsPassedThroughTheGapStraight) {
  // x = 5 is a wall but for (5, 8); the gap can only be entered and left
  // along the row (a diagonal into it would pass a wall cell's corner).
  Grid g = filled(11, 11, 0);
  for (int y = 0; y < 11; ++y) {
    if (y != 8) g.at(5, y) = kCostLethal;
  }
  GridPlanner planner(11, 11, 64);
  for (SearchMode mode : {SearchMode::kAStar, SearchMode::kDijkstra}) {
    const PlannerParams p = params(2.0, mode);
    const PlanResult r = planner.plan(g.view(), {1, 1}, {9, 1}, p);
    // (1,1) -> (4,8): 4 + 3 sqrt 2, (4,8) -> (6,8): 2, (6,8) -> (9,1): 4 + 3 sqrt 2.
    EXPECT_NEAR(r.cost, 10.0 + 6.0 * std::sqrt(2.0), 1e-12);
    expect_valid_path(g, r, {1, 1}, {9, 1}, p);
    bool through_gap = false;
    for (std::size_t i = 0; i < r.path_cells; ++i) through_gap = through_gap || r.path[i] == GridCell{5, 8};
    EXPECT_TRUE(through_gap);
  }
}

TEST(GridPlanner, AMazeOfOneCellCorridorsIsWalkedCellByCell) {
  const Grid g = picture({
      "S......#",
      "######.#",
      ".......#",
      ".#######",
      ".......G",
  });
  GridPlanner planner(8, 5, 64);
  const GridCell start{0, 4}, goal{7, 0};
  for (SearchMode mode : {SearchMode::kAStar, SearchMode::kDijkstra}) {
    const PlannerParams p = params(2.0, mode);
    const PlanResult r = planner.plan(g.view(), start, goal, p);
    EXPECT_DOUBLE_EQ(r.cost, 23.0);  // 6 + 2 + 6 + 2 + 7 steps, no diagonal at any turn
    EXPECT_EQ(r.path_cells, 24u);
    expect_valid_path(g, r, start, goal, p);
  }
}

TEST(GridPlanner, NoDiagonalStepCutsACorner) {
  Grid g = picture({
      "#.",
      ".#",
  });
  GridPlanner planner(2, 2, 8);
  const PlanResult blocked = planner.plan(g.view(), {0, 0}, {1, 1}, params(0.0));
  EXPECT_EQ(blocked.status, PlanStatus::kNoRoute);
  EXPECT_EQ(blocked.path_cells, 0u);
  EXPECT_EQ(blocked.path, nullptr);
  g.at(1, 0) = 0;  // one side open: around it, two steps, not sqrt 2
  const PlanResult around = planner.plan(g.view(), {0, 0}, {1, 1}, params(0.0));
  EXPECT_DOUBLE_EQ(around.cost, 2.0);
  EXPECT_EQ(around.path_cells, 3u);
  // Inscribed corners block as lethal ones do (lethal_from 253).
  g.at(1, 0) = kCostInscribed;
  EXPECT_EQ(planner.plan(g.view(), {0, 0}, {1, 1}, params(0.0)).status, PlanStatus::kNoRoute);
  // ...unless the inscribed zone is let in.
  PlannerParams p = params(0.0);
  p.passability.lethal_from = kCostLethal;
  EXPECT_DOUBLE_EQ(planner.plan(g.view(), {0, 0}, {1, 1}, p).cost, 2.0);
}

TEST(GridPlanner, ACheapDetourWinsWhenTheWeightSaysSo) {
  // Two routes: along the row of cost-126 cells (10 steps, 9 of them into
  // 'c') or around the wall over free cells (14 steps).
  const Grid g = picture({
      "...........",
      ".#########.",
      "ScccccccccG",
      "###########",
  });
  GridPlanner planner(11, 4, 64);
  const GridCell start{0, 1}, goal{10, 1};
  // Weight 2: each 'c' step costs 1 + 2 * 126 / 252 = 2: 19 against 14.
  const PlanResult heavy = planner.plan(g.view(), start, goal, params(2.0));
  EXPECT_DOUBLE_EQ(heavy.cost, 14.0);
  EXPECT_EQ(heavy.path[1], (GridCell{0, 2}));
  // Weight 0.5: 1.25 a step, 9 * 1.25 + 1 = 12.25 against 14.
  const PlanResult light = planner.plan(g.view(), start, goal, params(0.5));
  EXPECT_DOUBLE_EQ(light.cost, 12.25);
  EXPECT_EQ(light.path[1], (GridCell{1, 1}));
  // Weight 0: the cost only says passable; 10 steps.
  EXPECT_DOUBLE_EQ(planner.plan(g.view(), start, goal, params(0.0)).cost, 10.0);
  EXPECT_DOUBLE_EQ(planner.plan(g.view(), start, goal, params(2.0, SearchMode::kDijkstra)).cost, 14.0);
}

TEST(GridPlanner, UnknownCellsArePassableOnlyWhenAsked) {
  const Grid g = picture({
      "..........",
      ".########.",
      "S???????.G",
      "##########",
  });
  GridPlanner planner(10, 4, 64);
  const GridCell start{0, 1}, goal{9, 1};
  PlannerParams p = params(2.0);
  const PlanResult around = planner.plan(g.view(), start, goal, p);
  EXPECT_DOUBLE_EQ(around.cost, 13.0);  // up, along the top row, down: 2 + 9 + 2
  p.passability.unknown_passable = true;
  const PlanResult through = planner.plan(g.view(), start, goal, p);
  EXPECT_DOUBLE_EQ(through.cost, 9.0);  // unknown counted as cost 0
  expect_valid_path(g, through, start, goal, p);
  // A goal in unknown space: refused as unknown, or planned to.
  p.passability.unknown_passable = false;
  EXPECT_EQ(planner.plan(g.view(), start, {4, 1}, p).status, PlanStatus::kGoalUnknown);
  EXPECT_EQ(planner.plan(g.view(), {4, 1}, goal, p).status, PlanStatus::kStartBlocked);
  p.passability.unknown_passable = true;
  EXPECT_DOUBLE_EQ(planner.plan(g.view(), start, {4, 1}, p).cost, 4.0);
}

TEST(GridPlanner, EveryRefusalSaysWhy) {
  Grid g = picture({
      "....#...",
      "....#.i.",
      "....#.?.",
      "....#...",
  });
  g.at(1, 1) = kCostLethal;
  GridPlanner planner(10, 10, 6);
  const PlannerParams p = params(2.0);
  const CostView v = g.view();
  const auto status = [&](GridCell s, GridCell e, const PlannerParams& q) { return planner.plan(v, s, e, q).status; };
  EXPECT_EQ(status({0, 0}, {3, 3}, p), PlanStatus::kOk);
  EXPECT_EQ(status({-1, 0}, {3, 3}, p), PlanStatus::kStartOutsideGrid);
  EXPECT_EQ(status({8, 0}, {3, 3}, p), PlanStatus::kStartOutsideGrid);
  EXPECT_EQ(status({0, 4}, {3, 3}, p), PlanStatus::kStartOutsideGrid);
  EXPECT_EQ(status({0, 0}, {3, -1}, p), PlanStatus::kGoalOutsideGrid);
  EXPECT_EQ(status({0, 0}, {std::numeric_limits<int>::max(), 0}, p), PlanStatus::kGoalOutsideGrid);
  EXPECT_EQ(status({1, 1}, {3, 3}, p), PlanStatus::kStartBlocked);
  EXPECT_EQ(status({0, 0}, {1, 1}, p), PlanStatus::kGoalInObstacle);      // lethal
  EXPECT_EQ(status({7, 0}, {6, 2}, p), PlanStatus::kGoalInObstacle);      // inscribed
  EXPECT_EQ(status({7, 0}, {6, 1}, p), PlanStatus::kGoalUnknown);
  EXPECT_EQ(status({0, 0}, {7, 3}, p), PlanStatus::kNoRoute);             // behind the wall
  EXPECT_EQ(status({0, 0}, {3, 2}, p), PlanStatus::kOk);                  // 5 cells, around (1, 1)
  EXPECT_EQ(status({0, 3}, {3, 0}, p), PlanStatus::kOk);
  Grid corridor = filled(10, 1, 0);
  const PlanResult too_long = planner.plan(corridor.view(), {0, 0}, {9, 0}, p);  // 10 cells > 6
  EXPECT_EQ(too_long.status, PlanStatus::kPathTooLong);
  EXPECT_DOUBLE_EQ(too_long.cost, 9.0);  // the cost is still told
  EXPECT_EQ(too_long.path_cells, 0u);
  EXPECT_GT(too_long.expansions, 0u);
  Grid big = filled(11, 4, 0);
  EXPECT_EQ(planner.plan(big.view(), {0, 0}, {1, 1}, p).status, PlanStatus::kGridTooLarge);
  big = filled(4, 11, 0);
  EXPECT_EQ(planner.plan(big.view(), {0, 0}, {1, 1}, p).status, PlanStatus::kGridTooLarge);

  PlannerParams bad = p;
  for (double w : {std::nan(""), -1.0, std::numeric_limits<double>::infinity(), 2e6}) {
    bad.cost_weight = w;
    EXPECT_EQ(status({0, 0}, {3, 3}, bad), PlanStatus::kInvalidInput) << w;
  }
  bad = p;
  for (int lethal_from : {0, 255}) {
    bad.passability.lethal_from = static_cast<std::uint8_t>(lethal_from);
    EXPECT_EQ(status({0, 0}, {3, 3}, bad), PlanStatus::kInvalidInput) << lethal_from;
  }
  EXPECT_EQ(planner.plan(CostView{}, {0, 0}, {0, 0}, p).status, PlanStatus::kInvalidInput);
  EXPECT_EQ(planner.plan(CostView{g.cost.data(), 0, 4}, {0, 0}, {0, 0}, p).status, PlanStatus::kInvalidInput);
  EXPECT_EQ(planner.plan(CostView{g.cost.data(), 8, -4}, {0, 0}, {0, 0}, p).status, PlanStatus::kInvalidInput);

  // Each reason reads differently, none empty.
  std::set<std::string> texts;
  const PlanStatus all[] = {PlanStatus::kOk,          PlanStatus::kInvalidInput,     PlanStatus::kGridTooLarge,
                            PlanStatus::kStartOutsideGrid, PlanStatus::kGoalOutsideGrid, PlanStatus::kStartBlocked,
                            PlanStatus::kGoalInObstacle, PlanStatus::kGoalUnknown,    PlanStatus::kNoRoute,
                            PlanStatus::kPathTooLong, PlanStatus::kOpenListFull};
  for (PlanStatus s : all) {
    ASSERT_NE(to_string(s), nullptr);
    EXPECT_GT(std::strlen(to_string(s)), 0u);
    texts.insert(to_string(s));
  }
  EXPECT_EQ(texts.size(), std::size(all));
  EXPECT_STREQ(to_string(PlanStatus::kGoalInObstacle), "goal in an obstacle");
  EXPECT_STREQ(to_string(static_cast<PlanStatus>(200)), "unknown plan status");
}

TEST(GridPlanner, AWorkspaceIsSizedOnceAndRefusesNonsense) {
  EXPECT_THROW(GridPlanner(0, 10, 10), std::invalid_argument);
  EXPECT_THROW(GridPlanner(10, -1, 10), std::invalid_argument);
  EXPECT_THROW(GridPlanner(10, 10, 0), std::invalid_argument);
  EXPECT_THROW(GridPlanner(65536, 10, 10), std::invalid_argument);   // a side over 16 bits
  EXPECT_THROW(GridPlanner(20000, 20000, 10), std::invalid_argument);  // 2^28 cells or more
  const GridPlanner planner(400, 400, 4000);
  EXPECT_EQ(planner.max_width(), 400);
  EXPECT_EQ(planner.max_path_cells(), 4000u);
  EXPECT_GT(planner.workspace_bytes(), 400u * 400u * 16u);
}

TEST(GridPlanner, StepFactorsAreTheWeightedCost) {
  EXPECT_EQ(step_factor(0, 2.0), 1.0);
  EXPECT_EQ(step_factor(126, 2.0), 2.0);
  EXPECT_EQ(step_factor(252, 2.0), 3.0);
  EXPECT_EQ(step_factor(kCostUnknown, 2.0), 1.0);  // unknown, when passable, as free
  EXPECT_EQ(step_factor(200, 0.0), 1.0);
}

// Random grids: obstacles at a density, costs in 0..252 in patches, some
// inscribed and unknown cells. Raw mt19937 words (the same sequence under
// every standard library), so the pinned digest below holds everywhere.
struct Random {
  std::mt19937 rng;
  explicit Random(std::uint32_t seed) : rng(seed) {}
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(rng() % n); }
  bool chance(std::uint32_t percent) { return below(100) < percent; }
};

Grid random_grid(Random& r, int width, int height, std::uint32_t obstacle_percent) {
  Grid g = filled(width, height, 0);
  for (auto& c : g.cost) {
    if (r.chance(obstacle_percent)) {
      c = r.chance(80) ? kCostLethal : kCostInscribed;
    } else if (r.chance(5)) {
      c = kCostUnknown;
    } else if (r.chance(40)) {
      c = static_cast<std::uint8_t>(r.below(253));
    }
  }
  return g;
}

GridCell random_cell(Random& r, const Grid& g) {
  return GridCell{static_cast<int>(r.below(static_cast<std::uint32_t>(g.width))),
                  static_cast<int>(r.below(static_cast<std::uint32_t>(g.height)))};
}

TEST(GridPlanner, AStarAndDijkstraAgreeAndEveryPathIsAWalkOfTheGraph) {
  Random r(28);
  GridPlanner planner(48, 40, 48 * 40);
  int found = 0, no_route = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int w = 2 + static_cast<int>(r.below(47)), h = 1 + static_cast<int>(r.below(40));
    const Grid g = random_grid(r, w, h, r.below(40));
    PlannerParams p = params(r.chance(30) ? 0.0 : 0.25 * r.below(20));
    p.passability.unknown_passable = r.chance(50);
    const GridCell s = random_cell(r, g), e = random_cell(r, g);
    const PlanResult a = planner.plan(g.view(), s, e, p);
    p.mode = SearchMode::kDijkstra;
    const PlanResult d = planner.plan(g.view(), s, e, p);
    ASSERT_EQ(a.status, d.status) << "trial " << trial;
    if (!d.ok()) {
      no_route += d.status == PlanStatus::kNoRoute;
      continue;
    }
    ++found;
    EXPECT_NEAR(a.cost, d.cost, 1e-9 * d.cost) << "trial " << trial;
    EXPECT_LE(a.expansions, d.expansions);
    expect_valid_path(g, d, s, e, p);
    p.mode = SearchMode::kAStar;
    expect_valid_path(g, planner.plan(g.view(), s, e, p), s, e, p);
  }
  EXPECT_GT(found, 100);
  EXPECT_GT(no_route, 10);
}

TEST(GridPlanner, AFullOpenListDropsDeadEntriesAndPlansTheSame) {
  // The default open list (twice the cells) never runs out: it never holds
  // more than one needed entry per cell. One smaller than the grid fills
  // up; the entries it drops are dead ones (older entries of cells
  // improved since), skipped anyway, so paths, costs and expansions come
  // out the same, or, once only needed entries are left, the plan says so.
  Random r(99);
  GridPlanner roomy(40, 30, 1200);
  GridPlanner tight(40, 30, 1200, 64);
  std::size_t compacted = 0, same = 0, ran_out = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Grid g = random_grid(r, 40, 30, r.below(30));
    PlannerParams p = params(0.5 * r.below(10));
    p.mode = r.chance(50) ? SearchMode::kAStar : SearchMode::kDijkstra;
    const GridCell s = random_cell(r, g), e = random_cell(r, g);
    const PlanResult a = roomy.plan(g.view(), s, e, p);
    EXPECT_EQ(roomy.compactions(), 0u);
    const PlanResult b = tight.plan(g.view(), s, e, p);
    compacted += tight.compactions();
    if (b.status == PlanStatus::kOpenListFull) {
      ++ran_out;
      EXPECT_EQ(b.path_cells, 0u);
      continue;
    }
    ++same;
    ASSERT_EQ(a.status, b.status);
    EXPECT_EQ(a.expansions, b.expansions);
    EXPECT_EQ(a.cost, b.cost);
    ASSERT_EQ(a.path_cells, b.path_cells);
    for (std::size_t i = 0; i < a.path_cells; ++i) ASSERT_EQ(a.path[i], b.path[i]);
  }
  EXPECT_GT(compacted, 50u);
  EXPECT_GT(same, 100u);
  EXPECT_GT(ran_out, 5u);
}

TEST(GridPlanner, CostsOutliveThePlanBasesAndATooLongPathStillSaysItsCost) {
  // Many plans in a row cross the per-plan cost base's resets (every 31
  // plans); a goal never reached keeps an earlier plan's cost in its cell,
  // which must read as "not reached", never as a route. A path longer than
  // the buffer is refused with the search's cost, the optimum's.
  Grid g = filled(60, 40, 0);
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      if (dx != 0 || dy != 0) g.at(30 + dx, 20 + dy) = 254;
    }
  }
  const GridCell walled_in{30, 20};
  Random r(31);
  GridPlanner roomy(60, 40, 60 * 40);
  GridPlanner short_buffer(60, 40, 12);
  int too_long = 0;
  for (int k = 0; k < 200; ++k) {
    PlannerParams p = params(0.25 * r.below(12), r.chance(50) ? SearchMode::kAStar : SearchMode::kDijkstra);
    const GridCell s = random_cell(r, g), e = random_cell(r, g);
    if (g.at(s.x, s.y) != 0 || g.at(e.x, e.y) != 0 || s == walled_in || e == walled_in) continue;
    EXPECT_EQ(roomy.plan(g.view(), s, walled_in, p).status, PlanStatus::kNoRoute) << "plan " << k;
    const PlanResult a = roomy.plan(g.view(), s, e, p);
    ASSERT_TRUE(a.ok()) << "plan " << k;
    const PlanResult b = short_buffer.plan(g.view(), s, e, p);
    if (a.path_cells <= 12) {
      EXPECT_TRUE(b.ok()) << "plan " << k;
      continue;
    }
    ++too_long;
    EXPECT_EQ(b.status, PlanStatus::kPathTooLong) << "plan " << k;
    EXPECT_NEAR(b.cost, a.cost, 1e-9 * a.cost) << "plan " << k;
    EXPECT_EQ(b.path_cells, 0u);
  }
  EXPECT_GT(too_long, 100);
}

TEST(GridPlanner, TheCostWeightZeroIsThePlainGraph) {
  // A grid of costs with weight 0 plans as its free/lethal picture with any
  // weight: steps of 1 and sqrt 2.
  Random r(7);
  GridPlanner planner(40, 40, 1600);
  for (int trial = 0; trial < 50; ++trial) {
    const Grid g = random_grid(r, 40, 40, 25);
    Grid plain = g;
    for (auto& c : plain.cost) c = c == kCostUnknown ? kCostUnknown : c >= kCostInscribed ? kCostLethal : kCostFree;
    const GridCell s = random_cell(r, g), e = random_cell(r, g);
    const PlanResult weighted = planner.plan(g.view(), s, e, params(0.0));
    const double cost = weighted.cost;
    const PlanStatus status = weighted.status;
    const PlanResult binary = planner.plan(plain.view(), s, e, params(5.0));
    EXPECT_EQ(status, binary.status);
    EXPECT_NEAR(cost, binary.cost, 1e-9 * cost);
  }
}

// FNV-1a over the statuses, paths and the bits of the costs of a fixed set
// of plans: the same on every run, compiler and architecture (x86-64 here,
// aarch64 under tools/test-cross.sh).
std::uint64_t plan_digest(GridPlanner& planner) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      h ^= (v >> (8 * i)) & 0xFF;
      h *= 1099511628211ull;
    }
  };
  Random r(2028);
  for (int trial = 0; trial < 120; ++trial) {
    const Grid g = random_grid(r, 64, 48, r.below(35));
    // One draw a statement: the order of a call's arguments is the
    // compiler's choice, and GCC's is not clang's.
    PlannerParams p = params(0.5 * r.below(8));
    p.mode = r.chance(50) ? SearchMode::kAStar : SearchMode::kDijkstra;
    p.passability.unknown_passable = r.chance(50);
    const GridCell start = random_cell(r, g);
    const GridCell goal = random_cell(r, g);
    const PlanResult res = planner.plan(g.view(), start, goal, p);
    std::uint64_t bits = 0;
    std::memcpy(&bits, &res.cost, sizeof bits);
    mix(static_cast<std::uint64_t>(res.status));
    mix(bits);
    mix(res.expansions);
    for (std::size_t i = 0; i < res.path_cells; ++i) {
      mix((static_cast<std::uint64_t>(res.path[i].x) << 32) | static_cast<std::uint32_t>(res.path[i].y));
    }
  }
  return h;
}

TEST(GridPlanner, TheSamePathsOnEveryRunAndArchitecture) {
  GridPlanner a(64, 48, 64 * 48);
  const std::uint64_t first = plan_digest(a);
  EXPECT_EQ(plan_digest(a), first);  // the workspace's last plan changes nothing
  GridPlanner b(100, 100, 5000);
  EXPECT_EQ(plan_digest(b), first);  // nor its size
  EXPECT_EQ(first, 0x73a32c2d5e54ac40ull) << std::hex << first;
}

TEST(GridPlanner, PlanningAllocatesNothing) {
  Random r(3);
  const Grid g = random_grid(r, 200, 150, 20);
  const Grid open = filled(200, 150, 0);
  const Grid one = filled(1, 1, 0);
  GridPlanner planner(200, 150, 150);
  PlannerParams p = params(2.0);
  p.passability.unknown_passable = true;
  std::size_t plans = 0;
  rtfuse::test::AllocScope scope;
  for (int k = 0; k < 40; ++k) {
    p.mode = k % 2 ? SearchMode::kAStar : SearchMode::kDijkstra;
    const GridCell start = random_cell(r, g);
    const GridCell goal = random_cell(r, g);
    plans += planner.plan(g.view(), start, goal, p).ok();
  }
  const PlanStatus statuses[] = {
      planner.plan(open.view(), {0, 0}, {0, 149}, p).status,   // 150 cells: fits
      planner.plan(open.view(), {0, 0}, {199, 0}, p).status,   // 200 cells: too long
      planner.plan(open.view(), {0, 0}, {-1, 0}, p).status,
      planner.plan(one.view(), {0, 0}, {0, 0}, p).status,
      planner.plan(CostView{}, {0, 0}, {0, 0}, p).status,
  };
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(plans, 5u);
  EXPECT_EQ(statuses[0], PlanStatus::kOk);
  EXPECT_EQ(statuses[1], PlanStatus::kPathTooLong);
  EXPECT_EQ(statuses[2], PlanStatus::kGoalOutsideGrid);
  EXPECT_EQ(statuses[3], PlanStatus::kOk);
  EXPECT_EQ(statuses[4], PlanStatus::kInvalidInput);
}

}  // namespace grid_planner_test
