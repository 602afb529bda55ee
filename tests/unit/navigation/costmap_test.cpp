// The costmap from the occupancy grid: costmap_2d's costs at known
// distances, every cell against a brute-force nearest obstacle, updates
// against a costmap made anew, the unknown cells' three readings, no
// allocation, and parameters refused with the reason.
#include "navigation/costmap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "support/alloc_counter.hpp"

namespace costmap_test {

using namespace rtfuse::navigation;

CostmapParams robot() {
  CostmapParams p;
  p.resolution_m = 0.05;
  p.inscribed_radius_m = 0.2;
  p.inflation_radius_m = 0.55;
  p.cost_scaling_factor = 10.0;
  return p;
}

std::vector<std::int8_t> free_grid(int w, int h) { return std::vector<std::int8_t>(static_cast<std::size_t>(w) * h, 0); }

// What costmap_2d gives a free cell at d cells from the nearest obstacle
// cell, written out from its computeCost.
// Radii are whole cells when they are a rounding away from one (0.15 m at
// 0.05 m is 3 cells, not 2.9999999999999996).
int expected_cost(const CostmapParams& p, double d_cells) {
  const auto cells = [&](double m) {
    const double x = m / p.resolution_m;
    return std::fabs(x - std::round(x)) < 1e-9 ? std::round(x) : x;
  };
  const int radius = static_cast<int>(std::ceil(cells(p.inflation_radius_m)));
  if (d_cells == 0.0) return 254;
  if (d_cells > radius) return 0;
  if (d_cells <= cells(p.inscribed_radius_m) + 1e-12) return 253;
  return static_cast<int>(252.0 * std::exp(-p.cost_scaling_factor * (d_cells * p.resolution_m - p.inscribed_radius_m)));
}

TEST(Costmap, AnObstacleCellsCostsFallOffAsCostmap2dsInflation) {
  const int w = 60, h = 50;
  Costmap map(w, h, robot());
  std::vector<std::int8_t> grid = free_grid(w, h);
  grid[25 * w + 30] = 100;
  map.set_grid(grid.data());
  EXPECT_EQ(map.radius_cells(), 11);
  EXPECT_EQ(map.cost(30, 25), 254);
  EXPECT_EQ(map.cost(34, 25), 253);  // 0.20 m: inscribed
  EXPECT_EQ(map.cost(35, 25), 152);  // 0.25 m: 252 exp(-0.5) = 152.8
  EXPECT_EQ(map.cost(33, 29), 152);  // 3-4-5: 0.25 m again
  EXPECT_EQ(map.cost(41, 25), expected_cost(robot(), 11.0));
  EXPECT_GT(map.cost(41, 25), 0);
  EXPECT_EQ(map.cost(42, 25), 0);  // beyond 11 cells
  EXPECT_EQ(map.cost(38, 33), 0);  // 8-8: 11.3 cells
  EXPECT_EQ(map.cost(0, 0), 0);
}

// Every cell against the nearest obstacle found by looking at all of them.
void expect_brute_force(const Costmap& map, const std::vector<std::int8_t>& grid, int w, int h) {
  const CostmapParams& p = map.params();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double best = 1e9;
      for (int yo = 0; yo < h; ++yo) {
        for (int xo = 0; xo < w; ++xo) {
          if (grid[static_cast<std::size_t>(yo) * w + xo] >= p.occupied_from) {
            best = std::min(best, std::hypot(static_cast<double>(x - xo), static_cast<double>(y - yo)));
          }
        }
      }
      const std::int8_t value = grid[static_cast<std::size_t>(y) * w + x];
      const int inflated = best > 1e8 ? 0 : expected_cost(p, best);
      int want = inflated;
      if (value >= p.occupied_from) {
        want = 254;
      } else if (value < 0) {
        if (p.unknown == UnknownCells::kLethal) want = 254;
        if (p.unknown == UnknownCells::kNoInformation) want = inflated >= 253 ? inflated : 255;
      }
      ASSERT_EQ(static_cast<int>(map.cost(x, y)), want) << "cell " << x << ", " << y << ", nearest " << best;
    }
  }
}

std::vector<std::int8_t> random_grid(int w, int h, std::mt19937& rng) {
  std::vector<std::int8_t> grid(static_cast<std::size_t>(w) * h);
  std::uniform_int_distribution<int> kind(0, 99);
  for (std::int8_t& c : grid) {
    const int k = kind(rng);
    c = static_cast<std::int8_t>(k < 3 ? 100 : (k < 6 ? 70 : (k < 20 ? -1 : (k < 25 ? 50 : 0))));
  }
  return grid;
}

TEST(Costmap, EveryCellMatchesTheNearestObstacleFoundByBruteForce) {
  std::mt19937 rng(3);
  for (UnknownCells unknown : {UnknownCells::kNoInformation, UnknownCells::kFree, UnknownCells::kLethal}) {
    CostmapParams p = robot();
    p.unknown = unknown;
    p.inflation_radius_m = 0.3;  // 6 cells, so cells meet several obstacles
    const int w = 41, h = 37;
    Costmap map(w, h, p);
    const std::vector<std::int8_t> grid = random_grid(w, h, rng);
    map.set_grid(grid.data());
    expect_brute_force(map, grid, w, h);
  }
}

TEST(Costmap, UpdatesEqualACostmapMadeAnewAndRedoOnlyTilesNearChanges) {
  std::mt19937 rng(5);
  const int w = 150, h = 110;
  Costmap kept(w, h, robot());
  std::vector<std::int8_t> grid = random_grid(w, h, rng);
  kept.set_grid(grid.data());
  std::uniform_int_distribution<int> px(0, w - 1), py(0, h - 1), value(-1, 100);
  for (int round = 0; round < 30; ++round) {
    // A few changes in one place, as a map grows where the robot looks.
    const int cx = px(rng), cy = py(rng);
    for (int i = 0; i < 6; ++i) {
      const int x = std::clamp(cx + px(rng) % 7 - 3, 0, w - 1), y = std::clamp(cy + py(rng) % 7 - 3, 0, h - 1);
      grid[static_cast<std::size_t>(y) * w + x] = static_cast<std::int8_t>(value(rng));
    }
    const std::size_t changed = kept.update(grid.data());
    EXPECT_LE(changed, 6u);
    if (changed > 0) {
      EXPECT_LE(kept.tiles_redone(), 9u);  // a 7-cell patch and 11 cells around: 29 cells, 3 tiles a side at most
    }
    Costmap anew(w, h, robot());
    anew.set_grid(grid.data());
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) ASSERT_EQ(kept.cost(x, y), anew.cost(x, y)) << "round " << round << " cell " << x << ", " << y;
    }
  }
  // Nothing changed: nothing redone.
  EXPECT_EQ(kept.update(grid.data()), 0u);
  EXPECT_EQ(kept.tiles_redone(), 0u);
}

TEST(Costmap, ACellExactlyAtTheInscribedRadiusIsInscribed) {
  // 0.15 / 0.05 is 2.9999999999999996 and 3 x 0.05 is 0.15000000000000002:
  // the cell 3 cells away is inscribed all the same, and the one 4 away
  // (the inflation radius, 0.2 m) inflated.
  CostmapParams p = robot();
  p.inscribed_radius_m = 0.15;
  p.inflation_radius_m = 0.2;
  const int w = 20, h = 20;
  Costmap map(w, h, p);
  std::vector<std::int8_t> grid = free_grid(w, h);
  grid[10 * w + 10] = 100;
  map.set_grid(grid.data());
  EXPECT_EQ(map.radius_cells(), 4);
  EXPECT_EQ(map.cost(13, 10), 253);
  EXPECT_EQ(map.cost(14, 10), expected_cost(p, 4.0));
  EXPECT_LT(map.cost(14, 10), 253);
  EXPECT_EQ(map.cost(15, 10), 0);
}

TEST(Costmap, UnknownCellsReadAsConfigured) {
  const int w = 40, h = 20;
  std::vector<std::int8_t> grid(static_cast<std::size_t>(w) * h, -1);
  grid[10 * w + 10] = 100;
  for (UnknownCells unknown : {UnknownCells::kNoInformation, UnknownCells::kFree, UnknownCells::kLethal}) {
    CostmapParams p = robot();
    p.unknown = unknown;
    Costmap map(w, h, p);
    map.set_grid(grid.data());
    const int far = map.cost(30, 10), inscribed = map.cost(13, 10), inflated = map.cost(16, 10);
    if (unknown == UnknownCells::kNoInformation) {
      EXPECT_EQ(far, 255);
      EXPECT_EQ(inscribed, 253);  // costmap_2d: an unknown cell takes 253 and 254 only
      EXPECT_EQ(inflated, 255);
    } else if (unknown == UnknownCells::kFree) {
      EXPECT_EQ(far, 0);
      EXPECT_EQ(inscribed, 253);
      EXPECT_EQ(inflated, expected_cost(p, 6.0));
    } else {
      EXPECT_EQ(far, 254);
      EXPECT_EQ(inflated, 254);
    }
  }
}

TEST(Costmap, SetGridAndUpdateAllocateNothing) {
  const int w = 400, h = 400;
  Costmap map(w, h, robot());
  std::mt19937 rng(9);
  std::vector<std::int8_t> grid = random_grid(w, h, rng);
  rtfuse::test::AllocScope scope;
  map.set_grid(grid.data());
  grid[200 * w + 200] = 100;
  map.update(grid.data());
  EXPECT_EQ(scope.count(), 0u);
}

TEST(Costmap, ParametersThatCannotWorkAreRefusedWithTheReason) {
  CostmapParams p = robot();
  p.inflation_radius_m = 0.1;  // below the inscribed radius
  EXPECT_NE(check(p).find("inflation radius"), std::string::npos);
  EXPECT_THROW(Costmap(10, 10, p), std::invalid_argument);
  p = robot();
  p.resolution_m = std::nan("");
  EXPECT_NE(check(p).find("resolution"), std::string::npos);
  p = robot();
  p.inflation_radius_m = 20.0;
  EXPECT_FALSE(check(p).empty());
  p = robot();
  p.occupied_from = 0;
  EXPECT_NE(check(p).find("occupied_from"), std::string::npos);
  EXPECT_THROW(Costmap(0, 10, robot()), std::invalid_argument);
  EXPECT_TRUE(check(robot()).empty());
}

}  // namespace costmap_test
