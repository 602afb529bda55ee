// The path smoother and the segment walk under it: the walk visits exactly
// the cells whose closed square a segment meets (against a geometric test
// in exact integers), and smoothed paths on random grids keep every
// segment on passable cells, checked with that geometric test, not the walk.
#include "navigation/path_smoother.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "navigation/grid_line.hpp"
#include "navigation/grid_planner.hpp"
#include "support/alloc_counter.hpp"

namespace path_smoother_test {

using namespace rtfuse::navigation;

// Whether the segment between the centres of a and b meets the closed
// square of cell c: their boxes overlap and the segment's line does not
// leave all four corners strictly on one side. In doubled coordinates, so
// corners are integers and the test is exact.
bool touches(GridCell a, GridCell b, GridCell c) {
  if (std::min(a.x, b.x) * 2 > 2 * c.x + 1 || std::max(a.x, b.x) * 2 < 2 * c.x - 1) return false;
  if (std::min(a.y, b.y) * 2 > 2 * c.y + 1 || std::max(a.y, b.y) * 2 < 2 * c.y - 1) return false;
  const std::int64_t dx = 2 * (b.x - a.x), dy = 2 * (b.y - a.y);
  int positive = 0, negative = 0;
  for (int cx : {2 * c.x - 1, 2 * c.x + 1}) {
    for (int cy : {2 * c.y - 1, 2 * c.y + 1}) {
      const std::int64_t cross = dx * (cy - 2 * a.y) - dy * (cx - 2 * a.x);
      positive += cross > 0;
      negative += cross < 0;
    }
  }
  return positive < 4 && negative < 4;
}

std::vector<GridCell> walked(GridCell a, GridCell b) {
  std::vector<GridCell> cells;
  walk_segment(a, b, [&](GridCell c) {
    cells.push_back(c);
    return true;
  });
  return cells;
}

std::set<std::pair<int, int>> as_set(const std::vector<GridCell>& cells) {
  std::set<std::pair<int, int>> s;
  for (const GridCell& c : cells) s.insert({c.x, c.y});
  return s;
}

TEST(GridLine, SegmentsVisitTheirCellsOnceInOrder) {
  const std::vector<GridCell> row = walked({0, 0}, {3, 0});
  EXPECT_EQ(row.size(), 4u);
  EXPECT_EQ(row.back(), (GridCell{3, 0}));
  // A diagonal passes through corners: each one's two side cells too.
  EXPECT_EQ(as_set(walked({0, 0}, {2, 2})),
            (std::set<std::pair<int, int>>{{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 1}, {1, 2}, {2, 2}}));
  // A knight's move crosses two cells' borders and no corner.
  EXPECT_EQ(as_set(walked({0, 0}, {2, 1})), (std::set<std::pair<int, int>>{{0, 0}, {1, 0}, {1, 1}, {2, 1}}));
  EXPECT_EQ(walked({5, -3}, {5, -3}).size(), 1u);
  int calls = 0;
  EXPECT_FALSE(walk_segment({0, 0}, {9, 0}, [&](GridCell) { return ++calls < 3; }));
  EXPECT_EQ(calls, 3);
}

TEST(GridLine, TheWalkIsTheSetOfCellsTheSegmentTouches) {
  std::mt19937 rng(11);
  const auto coordinate = [&rng] { return static_cast<int>(rng() % 41) - 20; };
  for (int trial = 0; trial < 3000; ++trial) {
    const GridCell a{coordinate(), coordinate()};
    const GridCell b = trial % 5 == 0 ? GridCell{a.x + (coordinate() % 6), a.y + (coordinate() % 6)}
                                      : GridCell{coordinate(), coordinate()};
    const std::vector<GridCell> cells = walked(a, b);
    ASSERT_EQ(cells.front(), a);
    ASSERT_EQ(cells.back(), b);
    const std::set<std::pair<int, int>> visited = as_set(cells);
    ASSERT_EQ(visited.size(), cells.size()) << "a cell visited twice";
    std::set<std::pair<int, int>> touched;
    for (int y = std::min(a.y, b.y) - 1; y <= std::max(a.y, b.y) + 1; ++y) {
      for (int x = std::min(a.x, b.x) - 1; x <= std::max(a.x, b.x) + 1; ++x) {
        if (touches(a, b, {x, y})) touched.insert({x, y});
      }
    }
    ASSERT_EQ(visited, touched) << "(" << a.x << ", " << a.y << ") -> (" << b.x << ", " << b.y << ")";
  }
}

struct Grid {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> cost;
  CostView view() const { return CostView{cost.data(), width, height}; }
};

Grid random_grid(std::mt19937& rng, int width, int height, unsigned obstacle_percent) {
  Grid g{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height, 0)};
  for (auto& c : g.cost) {
    const unsigned roll = rng() % 100;
    if (roll < obstacle_percent) {
      c = roll % 4 == 0 ? kCostInscribed : kCostLethal;
    } else if (roll > 96) {
      c = kCostUnknown;
    } else if (roll > 70) {
      c = static_cast<std::uint8_t>(rng() % 253);
    }
  }
  // Boxes: long walls and corners for the segments to graze.
  for (int box = 0; box < 4; ++box) {
    const int x0 = static_cast<int>(rng() % static_cast<unsigned>(width));
    const int y0 = static_cast<int>(rng() % static_cast<unsigned>(height));
    const int bw = 1 + static_cast<int>(rng() % 8), bh = 1 + static_cast<int>(rng() % 8);
    for (int y = y0; y < std::min(height, y0 + bh); ++y) {
      for (int x = x0; x < std::min(width, x0 + bw); ++x) g.cost[static_cast<std::size_t>(y) * width + x] = kCostLethal;
    }
  }
  return g;
}

// Every cell the segment touches, found geometrically, is passable.
bool clear_geometrically(const Grid& g, const Passability& rule, GridCell a, GridCell b) {
  for (int y = std::min(a.y, b.y) - 1; y <= std::max(a.y, b.y) + 1; ++y) {
    for (int x = std::min(a.x, b.x) - 1; x <= std::max(a.x, b.x) + 1; ++x) {
      if (!touches(a, b, {x, y})) continue;
      if (x < 0 || y < 0 || x >= g.width || y >= g.height) return false;
      if (!rule.passable(g.view().at(x, y))) return false;
    }
  }
  return true;
}

TEST(PathSmoother, AnOpenGridsPathIsOneSegment) {
  const Grid g{20, 10, std::vector<std::uint8_t>(200, 0)};
  GridPlanner planner(20, 10, 64);
  const PlanResult r = planner.plan(g.view(), {0, 0}, {19, 6}, PlannerParams{});
  ASSERT_TRUE(r.ok());
  std::vector<GridCell> out(r.path_cells);
  ASSERT_EQ(smooth_path(g.view(), Passability{}, r.path, r.path_cells, out.data()), 2u);
  EXPECT_EQ(out[0], (GridCell{0, 0}));
  EXPECT_EQ(out[1], (GridCell{19, 6}));
}

TEST(PathSmoother, ACornerIsKeptWhereTheStraightLineWouldCutIt) {
  // An L: the straight line from start to goal crosses the block.
  Grid g{10, 10, std::vector<std::uint8_t>(100, 0)};
  for (int y = 0; y < 8; ++y) {
    for (int x = 2; x < 10; ++x) g.cost[static_cast<std::size_t>(y) * 10 + x] = kCostLethal;
  }
  GridPlanner planner(10, 10, 64);
  const PlanResult r = planner.plan(g.view(), {0, 0}, {9, 9}, PlannerParams{});
  ASSERT_TRUE(r.ok());
  std::vector<GridCell> out(r.path_cells);
  const std::size_t kept = smooth_path(g.view(), Passability{}, r.path, r.path_cells, out.data());
  EXPECT_GE(kept, 3u);
  EXPECT_LT(kept, r.path_cells);
  for (std::size_t i = 1; i < kept; ++i) EXPECT_TRUE(clear_geometrically(g, Passability{}, out[i - 1], out[i]));
  EXPECT_FALSE(segment_passable(g.view(), Passability{}, {0, 0}, {9, 9}));
  EXPECT_FALSE(segment_passable(g.view(), Passability{}, {0, 0}, {10, 0}));  // leaves the grid
  EXPECT_FALSE(segment_passable(CostView{}, Passability{}, {0, 0}, {0, 0}));
  EXPECT_TRUE(segment_passable(g.view(), Passability{}, {0, 9}, {9, 9}));
}

TEST(PathSmoother, SmoothedPathsOnRandomGridsNeverCollide) {
  std::mt19937 rng(28);
  GridPlanner planner(60, 60, 3600);
  std::vector<GridCell> out(3600), in_place(3600);
  std::size_t smoothed = 0, waypoints_in = 0, waypoints_out = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int w = 5 + static_cast<int>(rng() % 56), h = 5 + static_cast<int>(rng() % 56);
    const Grid g = random_grid(rng, w, h, rng() % 30);
    PlannerParams p;
    p.cost_weight = 0.5 * (rng() % 6);
    p.passability.unknown_passable = rng() % 2 == 0;
    p.passability.lethal_from = rng() % 3 == 0 ? kCostLethal : kCostInscribed;
    const auto cell = [&rng, w, h] {
      const int x = static_cast<int>(rng() % static_cast<unsigned>(w));
      return GridCell{x, static_cast<int>(rng() % static_cast<unsigned>(h))};
    };
    const GridCell s = cell();
    const GridCell e = cell();
    const PlanResult r = planner.plan(g.view(), s, e, p);
    if (!r.ok()) continue;
    const std::size_t kept = smooth_path(g.view(), p.passability, r.path, r.path_cells, out.data());
    ASSERT_GE(kept, std::min<std::size_t>(r.path_cells, 2));
    ASSERT_LE(kept, r.path_cells);
    EXPECT_EQ(out[0], s);
    EXPECT_EQ(out[kept - 1], e);
    // Kept waypoints are the path's, in its order.
    std::size_t at = 0;
    for (std::size_t k = 0; k < kept; ++k) {
      while (at < r.path_cells && r.path[at] != out[k]) ++at;
      ASSERT_LT(at, r.path_cells) << "waypoint " << k << " is not on the path, in order";
    }
    for (std::size_t k = 1; k < kept; ++k) {
      ASSERT_TRUE(clear_geometrically(g, p.passability, out[k - 1], out[k]))
          << "trial " << trial << ": segment (" << out[k - 1].x << ", " << out[k - 1].y << ") -> (" << out[k].x
          << ", " << out[k].y << ") touches a blocked cell";
    }
    // In place gives the same waypoints.
    std::copy(r.path, r.path + r.path_cells, in_place.begin());
    ASSERT_EQ(smooth_path(g.view(), p.passability, in_place.data(), r.path_cells, in_place.data()), kept);
    ASSERT_TRUE(std::equal(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(kept), in_place.begin()));
    ++smoothed;
    waypoints_in += r.path_cells;
    waypoints_out += kept;
  }
  EXPECT_GT(smoothed, 200u);
  EXPECT_LT(waypoints_out * 3, waypoints_in);  // it does smooth
}

TEST(PathSmoother, ShortPathsComeBackAsTheyWereAndNothingIsAllocated) {
  const Grid g{4, 4, std::vector<std::uint8_t>(16, 0)};
  const GridCell path[] = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  GridCell out[4] = {};
  rtfuse::test::AllocScope scope;
  const std::size_t none = smooth_path(g.view(), Passability{}, path, 0, out);
  const std::size_t one = smooth_path(g.view(), Passability{}, path, 1, out);
  const std::size_t two = smooth_path(g.view(), Passability{}, path, 2, out);
  const std::size_t four = smooth_path(g.view(), Passability{}, path, 4, out);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(none, 0u);
  EXPECT_EQ(one, 1u);
  EXPECT_EQ(two, 2u);
  EXPECT_EQ(four, 2u);
  EXPECT_EQ(out[1], (GridCell{3, 3}));
}

}  // namespace path_smoother_test
