#pragma once
// A costmap like one a robot builds of a room, for the grid planner's
// benchmark and its reference test: 400 x 400 cells (20 m at 0.05 m) of an
// occupancy grid with walls round it, boxes, pillars, patches never seen
// (unknown) and, unless asked not to, four long inner walls with two
// doorways each (the routes then detour, and A* searches much of the
// room), made into costmap_2d's costs by navigation::Costmap with its
// defaults (inscribed radius 0.2 m, inflation 0.55 m, scaling 10, unknown
// as no information), and fixed start/goal pairs on passable cells. Raw
// mt19937 words only, so the same map and pairs under every standard
// library.
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "navigation/cost_values.hpp"
#include "navigation/costmap.hpp"
#include "navigation/grid_cell.hpp"

namespace rtfuse::test {

struct SyntheticCostmap {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> cost;
  std::vector<navigation::GridCell> starts;
  std::vector<navigation::GridCell> goals;

  navigation::CostView view() const { return navigation::CostView{cost.data(), width, height}; }
};

// The costs of a size x size occupancy grid (nav_msgs/OccupancyGrid
// values) by navigation::Costmap with its defaults; no pairs yet.
inline SyntheticCostmap costmap_of_grid(const std::vector<std::int8_t>& grid, int size) {
  navigation::Costmap costmap(size, size, navigation::CostmapParams{});
  costmap.set_grid(grid.data());
  SyntheticCostmap out;
  out.width = size;
  out.height = size;
  out.cost.assign(costmap.view().cost, costmap.view().cost + grid.size());
  return out;
}

inline SyntheticCostmap synthetic_costmap(bool inner_walls = true, int size = 400, std::size_t pairs = 100,
                                          std::uint32_t seed = 28) {
  std::mt19937 rng(seed);
  const auto below = [&rng](int n) { return static_cast<int>(rng() % static_cast<std::uint32_t>(n)); };
  std::vector<std::int8_t> grid(static_cast<std::size_t>(size) * static_cast<std::size_t>(size), 0);
  const auto fill = [&](int x0, int y0, int x1, int y1, std::int8_t value) {  // [x0, x1) x [y0, y1), clipped
    for (int y = std::max(0, y0); y < std::min(size, y1); ++y) {
      for (int x = std::max(0, x0); x < std::min(size, x1); ++x) {
        grid[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)] = value;
      }
    }
  };
  fill(0, 0, size, 2, 100);  // the room's walls
  fill(0, size - 2, size, size, 100);
  fill(0, 0, 2, size, 100);
  fill(size - 2, 0, size, size, 100);
  // Inner walls across part of the room, each with two doorways 0.8 m wide
  // (drawn or not, the same random words are taken: the rest is the same).
  for (int wall = 0; wall < 4; ++wall) {
    const int at = size / 5 + below(3 * size / 5);
    const int from = below(size / 3);
    const int to = size - below(size / 3);
    const int door1 = from + below(std::max(1, (to - from) / 2 - 16));
    const int door2 = (from + to) / 2 + below(std::max(1, (to - from) / 2 - 16));
    for (int s = from; s < to && inner_walls; ++s) {
      if ((s >= door1 && s < door1 + 16) || (s >= door2 && s < door2 + 16)) continue;
      if (wall % 2 == 0) {
        fill(s, at, s + 1, at + 2, 100);
      } else {
        fill(at, s, at + 2, s + 1, 100);
      }
    }
  }
  for (int box = 0; box < 25; ++box) {  // furniture: 0.2 to 2 m
    const int x = below(size), y = below(size);
    const int w = 4 + below(37);
    const int h = 4 + below(37);
    fill(x, y, x + w, y + h, 100);
  }
  for (int pillar = 0; pillar < 60; ++pillar) {  // discs of 1 to 3 cells' radius
    const int cx = below(size), cy = below(size), r = 1 + below(3);
    for (int y = cy - r; y <= cy + r; ++y) {
      for (int x = cx - r; x <= cx + r; ++x) {
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r) fill(x, y, x + 1, y + 1, 100);
      }
    }
  }
  for (int patch = 0; patch < 3; ++patch) {  // never seen
    const int x = below(size), y = below(size);
    const int w = 20 + below(31);
    const int h = 20 + below(31);
    fill(x, y, x + w, y + h, -1);
  }

  SyntheticCostmap out = costmap_of_grid(grid, size);
  const auto passable_cell = [&] {
    for (;;) {
      const int x = below(size);
      const int y = below(size);
      if (out.cost[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)] <
          navigation::kCostInscribed) {
        return navigation::GridCell{x, y};
      }
    }
  };
  for (std::size_t i = 0; i < pairs; ++i) {
    out.starts.push_back(passable_cell());
    out.goals.push_back(passable_cell());
  }
  return out;
}

}  // namespace rtfuse::test
