// The check that stops the follower on an obstacle the map reveals: which
// costs block, where the checked distance ends, the grid's edge, bad input
// counted as blocked, and, on random grids and pieces between arbitrary
// points, exactly the cells whose closed square a piece meets (an exact
// integer test, not the walk), the same cells as grid_line.hpp's walk
// between cell centres; no allocation.
#include "navigation/path_clearance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "navigation/grid_line.hpp"
#include "support/alloc_counter.hpp"

namespace path_clearance_test {

using namespace rtfuse::navigation;

struct Grid {
  int width = 0, height = 0;
  std::vector<std::uint8_t> cost;
  Grid(int w, int h, std::uint8_t fill = kCostFree) : width(w), height(h), cost(static_cast<std::size_t>(w) * h, fill) {}
  std::uint8_t& at(int x, int y) { return cost[static_cast<std::size_t>(y) * width + x]; }
  CostView view() const { return CostView{cost.data(), width, height}; }
};

// 40 x 40 cells of 5 cm: [-1, 1] m on both axes; cell (20, 20) holds (0, 0)
// to (0.05, 0.05).
const GridGeometry kGeometry{-1.0, -1.0, 0.05};

bool blocked(const Grid& g, const std::vector<Point2>& path, double distance, std::uint8_t lethal_from = 253,
             int from_index = 0) {
  return path_blocked(g.view(), kGeometry, path.data(), static_cast<int>(path.size()), from_index, path[from_index],
                      distance, lethal_from);
}

// A path along y = 0.025 (the middle of row 20) from x = -0.5 to 0.5.
const std::vector<Point2> kStraight{{-0.5, 0.025}, {0.0, 0.025}, {0.5, 0.025}};

TEST(PathClearance, AClearPathIsClear) {
  const Grid g(40, 40);
  EXPECT_FALSE(blocked(g, kStraight, 1.0));
  EXPECT_FALSE(blocked(g, kStraight, std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(blocked(g, kStraight, 0.0));
}

TEST(PathClearance, AnObstacleWithinTheDistanceBlocksOneBeyondItDoesNot) {
  Grid g(40, 40);
  g.at(26, 20) = kCostLethal;  // x in [0.30, 0.35): 0.80 m along the path
  EXPECT_TRUE(blocked(g, kStraight, 1.0));
  EXPECT_TRUE(blocked(g, kStraight, 0.81));
  EXPECT_FALSE(blocked(g, kStraight, 0.79));
  // Behind the robot: from (0.4, 0.025) on the second segment, it is passed.
  EXPECT_FALSE(path_blocked(g.view(), kGeometry, kStraight.data(), 3, 1, Point2{0.4, 0.025}, 1.0, 253));
  // The nearest point itself in it.
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, kStraight.data(), 3, 1, Point2{0.32, 0.025}, 0.0, 253));
}

TEST(PathClearance, TheInscribedZoneAndUnknownBlockInflationDoesNot) {
  Grid g(40, 40);
  g.at(22, 20) = kCostInflatedMax;
  EXPECT_FALSE(blocked(g, kStraight, 2.0));
  g.at(22, 20) = kCostInscribed;
  EXPECT_TRUE(blocked(g, kStraight, 2.0));
  EXPECT_FALSE(blocked(g, kStraight, 2.0, kCostLethal));  // a costmap that inscribes nothing
  g.at(22, 20) = kCostUnknown;
  EXPECT_TRUE(blocked(g, kStraight, 2.0));
  EXPECT_TRUE(blocked(g, kStraight, 2.0, kCostLethal));
  g.at(22, 20) = 100;
  EXPECT_TRUE(blocked(g, kStraight, 2.0, 100));
  EXPECT_FALSE(blocked(g, kStraight, 2.0, 101));
}

TEST(PathClearance, LeavingTheGridBlocksWithinTheDistanceOnly) {
  const Grid g(40, 40);
  const std::vector<Point2> out{{0.0, 0.0}, {0.9, 0.0}, {1.5, 0.0}};  // the grid ends at x = 1
  EXPECT_TRUE(blocked(g, out, 1.2));
  EXPECT_FALSE(blocked(g, out, 0.95));
  const std::vector<Point2> outside{{1.5, 0.0}, {0.0, 0.0}};
  EXPECT_TRUE(blocked(g, outside, 1.0));
  // The grid's cells are [origin, origin + size): x = 1.0 is outside.
  EXPECT_TRUE(blocked(g, std::vector<Point2>{{0.0, 0.0}, {1.0, 0.0}}, 5.0));
  EXPECT_FALSE(blocked(g, std::vector<Point2>{{0.0, 0.0}, {0.999, 0.0}}, 5.0));
  // Huge and tiny numbers are outside, not overflows.
  EXPECT_TRUE(blocked(g, std::vector<Point2>{{0.0, 0.0}, {9e5, -9e5}}, 1e9));
  const GridGeometry tiny{-1.0, -1.0, 1e-300};
  EXPECT_TRUE(path_blocked(g.view(), tiny, kStraight.data(), 3, 0, kStraight[0], 1.0, 253));
}

TEST(PathClearance, ADiagonalThroughACornerTouchesTheCellsBesideIt) {
  Grid g(40, 40);
  // From the centre of (20, 20) to that of (22, 22): through the corners
  // at (21, 21)'s. Cell (21, 20) beside the first corner is touched.
  const std::vector<Point2> diagonal{{0.025, 0.025}, {0.125, 0.125}};
  EXPECT_FALSE(blocked(g, diagonal, 1.0));
  g.at(21, 20) = kCostLethal;
  EXPECT_TRUE(blocked(g, diagonal, 1.0));
  // A piece along a cell border touches both rows.
  Grid h(40, 40);
  h.at(22, 19) = kCostLethal;
  EXPECT_TRUE(blocked(h, std::vector<Point2>{{0.0, 0.0}, {0.3, 0.0}}, 1.0));
  EXPECT_FALSE(blocked(h, std::vector<Point2>{{0.0, 0.001}, {0.3, 0.001}}, 1.0));
}

TEST(PathClearance, TheLastPieceIsCutWhereTheDistanceEnds) {
  Grid g(40, 40);
  g.at(30, 20) = kCostLethal;  // x in [0.50, 0.55)
  const std::vector<Point2> longer{{-0.5, 0.025}, {0.9, 0.025}};
  EXPECT_FALSE(blocked(g, longer, 0.99));
  EXPECT_TRUE(blocked(g, longer, 1.01));
  // Repeated points use none of the distance.
  const std::vector<Point2> repeated{{-0.5, 0.025}, {-0.5, 0.025}, {-0.5, 0.025}, {0.9, 0.025}};
  EXPECT_FALSE(blocked(g, repeated, 0.99));
  EXPECT_TRUE(blocked(g, repeated, 1.01));
}

TEST(PathClearance, WhatCannotBeCheckedIsBlocked) {
  const Grid g(40, 40);
  const Point2* p = kStraight.data();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(path_blocked(CostView{}, kGeometry, p, 3, 0, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, nullptr, 3, 0, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 0, 0, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 3, 3, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 3, -1, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 3, 0, Point2{nan, 0.0}, 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 3, 0, p[0], nan, 253));
  EXPECT_TRUE(path_blocked(g.view(), kGeometry, p, 3, 0, p[0], 1.0, 0));
  EXPECT_TRUE(path_blocked(g.view(), GridGeometry{-1.0, -1.0, 0.0}, p, 3, 0, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), GridGeometry{-1.0, -1.0, -0.05}, p, 3, 0, p[0], 1.0, 253));
  EXPECT_TRUE(path_blocked(g.view(), GridGeometry{nan, -1.0, 0.05}, p, 3, 0, p[0], 1.0, 253));
  const std::vector<Point2> bad{{0.0, 0.0}, {0.1, std::numeric_limits<double>::infinity()}};
  EXPECT_TRUE(blocked(g, bad, 1.0));
  // A negative distance checks the nearest point's cell only.
  EXPECT_FALSE(blocked(g, kStraight, -1.0));
}

// In units of 1/8 of a cell: whether the segment p-q meets the closed
// square of cell (cx, cy). Separating axes: the boxes overlap and the
// segment's line leaves not all four corners strictly on one side.
bool touches(std::int64_t px, std::int64_t py, std::int64_t qx, std::int64_t qy, int cx, int cy) {
  const std::int64_t x0 = 8 * cx, x1 = 8 * cx + 8, y0 = 8 * cy, y1 = 8 * cy + 8;
  if (std::min(px, qx) > x1 || std::max(px, qx) < x0 || std::min(py, qy) > y1 || std::max(py, qy) < y0) return false;
  int positive = 0, negative = 0;
  for (std::int64_t x : {x0, x1}) {
    for (std::int64_t y : {y0, y1}) {
      const std::int64_t cross = (qx - px) * (y - py) - (qy - py) * (x - px);
      positive += cross > 0;
      negative += cross < 0;
    }
  }
  return positive < 4 && negative < 4;
}

TEST(PathClearance, PiecesBlockExactlyWhereTheyMeetABlockingCell) {
  // Cells of 0.25 m from the origin: points on a 1/8-cell lattice are exact
  // in binary, so the test's integers are the points' own.
  const GridGeometry geometry{0.0, 0.0, 0.25};
  std::mt19937 rng(28);
  const int w = 24, h = 20;
  int blocked_count = 0, compared = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Grid g(w, h);
    const int obstacles = 4 + static_cast<int>(rng() % 16);
    for (int k = 0; k < obstacles; ++k) g.at(static_cast<int>(rng() % w), static_cast<int>(rng() % h)) = kCostLethal;
    // Arbitrary points; every fifth trial cell centres, every seventh a
    // piece along a border.
    const auto lattice = [&](int cells) { return static_cast<std::int64_t>(rng() % (8 * cells)); };
    std::int64_t px = lattice(w), py = lattice(h), qx = lattice(w), qy = lattice(h);
    if (trial % 5 == 0) {
      px = px / 8 * 8 + 4, py = py / 8 * 8 + 4, qx = qx / 8 * 8 + 4, qy = qy / 8 * 8 + 4;
    } else if (trial % 7 == 0) {
      py = qy = py / 8 * 8;
    }
    const std::vector<Point2> path{{px / 32.0, py / 32.0}, {qx / 32.0, qy / 32.0}};
    bool expected = false;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) expected = expected || (g.at(x, y) >= 253 && touches(px, py, qx, qy, x, y));
    }
    const bool got = path_blocked(g.view(), geometry, path.data(), 2, 0, path[0],
                                  std::numeric_limits<double>::infinity(), 253);
    ASSERT_EQ(got, expected) << "trial " << trial << ": (" << px << ", " << py << ") to (" << qx << ", " << qy
                             << ") in eighths of a cell";
    if (trial % 5 == 0) {  // between centres: the cells grid_line.hpp's walk visits
      bool walked = false;
      walk_segment(GridCell{static_cast<int>(px / 8), static_cast<int>(py / 8)},
                   GridCell{static_cast<int>(qx / 8), static_cast<int>(qy / 8)}, [&](GridCell c) {
                     walked = walked || g.at(c.x, c.y) >= 253;
                     return true;
                   });
      EXPECT_EQ(got, walked) << "trial " << trial;
      ++compared;
    }
    blocked_count += got;
  }
  // Both outcomes are common enough to mean something.
  EXPECT_GT(blocked_count, 1000);
  EXPECT_LT(blocked_count, 3000);
  EXPECT_EQ(compared, 800);
}

TEST(PathClearance, CheckingAllocatesNothing) {
  Grid g(40, 40);
  g.at(30, 30) = kCostLethal;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(-1.2, 1.2);
  std::vector<Point2> path(50);
  for (Point2& p : path) p = Point2{coordinate(rng), coordinate(rng)};
  int count = 0;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 49; ++i) count += blocked(g, path, 0.5 + i * 0.1, 253, i);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(count, 0);
}

}  // namespace path_clearance_test
