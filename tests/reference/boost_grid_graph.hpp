#pragma once
// The grid planner's graph built for Boost Graph (Debian's
// libboost-graph-dev, test-only), for the reference test and the
// benchmark: the same vertices (every cell, y * width + x), the same edges
// and weights as navigation/grid_planner.hpp defines them, written out
// here again from that definition rather than taken from the planner:
//   - a cell is passable when its cost is below lethal_from, unknown (255)
//     only when unknown_passable;
//   - 8 neighbours, a diagonal only when both cells beside it are passable;
//   - weight = (1 or sqrt 2) * (1 + cost_weight * cost / 252), cost the
//     target's, unknown as 0.
// Stored as Boost's compressed sparse row graph, its fastest for a graph
// that does not change; built once per grid, outside anything timed.
#include <boost/graph/astar_search.hpp>
#include <boost/graph/compressed_sparse_row_graph.hpp>
#include <boost/graph/dijkstra_shortest_paths.hpp>
#include <boost/property_map/property_map.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

#include "navigation/cost_values.hpp"
#include "navigation/grid_planner.hpp"

namespace rtfuse::test {

struct BoostGridEdge {
  double weight = 0.0;
};
using BoostGridGraph = boost::compressed_sparse_row_graph<boost::directedS, boost::no_property, BoostGridEdge>;
using BoostVertex = boost::graph_traits<BoostGridGraph>::vertex_descriptor;

inline BoostGridGraph boost_grid_graph(const navigation::CostView& grid, const navigation::PlannerParams& params) {
  const auto passable = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= grid.width || y >= grid.height) return false;
    const std::uint8_t c = grid.at(x, y);
    if (c == 255) return params.passability.unknown_passable;
    return c < params.passability.lethal_from;
  };
  const auto factor = [&](int x, int y) {
    const std::uint8_t c = grid.at(x, y);
    const double cost = c == 255 ? 0.0 : static_cast<double>(c);
    return 1.0 + params.cost_weight * cost / 252.0;
  };
  std::vector<std::pair<BoostVertex, BoostVertex>> edges;
  std::vector<BoostGridEdge> weights;
  for (int y = 0; y < grid.height; ++y) {
    for (int x = 0; x < grid.width; ++x) {
      if (!passable(x, y)) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx == 0 && dy == 0) || !passable(x + dx, y + dy)) continue;
          const bool diagonal = dx != 0 && dy != 0;
          if (diagonal && !(passable(x + dx, y) && passable(x, y + dy))) continue;
          edges.emplace_back(static_cast<BoostVertex>(y * grid.width + x),
                             static_cast<BoostVertex>((y + dy) * grid.width + x + dx));
          weights.push_back({(diagonal ? std::sqrt(2.0) : 1.0) * factor(x + dx, y + dy)});
        }
      }
    }
  }
  // Edges come out in order of their source: Boost's sorted constructor.
  return BoostGridGraph(boost::edges_are_sorted, edges.begin(), edges.end(), weights.begin(),
                        static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height));
}

inline constexpr double kBoostUnreached = std::numeric_limits<double>::max();

// boost::dijkstra_shortest_paths from start: every cell's distance,
// kBoostUnreached where there is no route.
inline std::vector<double> boost_distances(const BoostGridGraph& g, BoostVertex start) {
  std::vector<double> distance(boost::num_vertices(g));
  boost::dijkstra_shortest_paths(
      g, start,
      boost::distance_map(boost::make_iterator_property_map(distance.begin(), boost::get(boost::vertex_index, g)))
          .weight_map(boost::get(&BoostGridEdge::weight, g)));
  return distance;
}

// boost::astar_search between two cells, as Boost's own examples stop it
// at the goal (a visitor that throws), with the same octile heuristic. Its
// property maps are the caller's, sized once: what a user who plans often
// would do.
class BoostAStar {
 public:
  explicit BoostAStar(const BoostGridGraph& g, int width)
      : g_(g),
        width_(width),
        predecessor_(boost::num_vertices(g)),
        distance_(boost::num_vertices(g)),
        rank_(boost::num_vertices(g)),
        color_(boost::num_vertices(g)) {}

  // The goal's distance, or kBoostUnreached.
  double plan(BoostVertex start, BoostVertex goal) {
    const auto index = boost::get(boost::vertex_index, g_);
    try {
      boost::astar_search(g_, start, Octile(width_, goal),
                          boost::predecessor_map(boost::make_iterator_property_map(predecessor_.begin(), index))
                              .distance_map(boost::make_iterator_property_map(distance_.begin(), index))
                              .rank_map(boost::make_iterator_property_map(rank_.begin(), index))
                              .color_map(boost::make_iterator_property_map(color_.begin(), index))
                              .weight_map(boost::get(&BoostGridEdge::weight, g_))
                              .visitor(StopAtGoal(goal)));
    } catch (const FoundGoal&) {
      return distance_[goal];
    }
    return kBoostUnreached;
  }

 private:
  struct FoundGoal {};
  class StopAtGoal : public boost::default_astar_visitor {
   public:
    explicit StopAtGoal(BoostVertex goal) : goal_(goal) {}
    void examine_vertex(BoostVertex u, const BoostGridGraph&) const {
      if (u == goal_) throw FoundGoal{};
    }

   private:
    BoostVertex goal_;
  };
  class Octile : public boost::astar_heuristic<BoostGridGraph, double> {
   public:
    Octile(int width, BoostVertex goal)
        : width_(width), gx_(static_cast<int>(goal) % width), gy_(static_cast<int>(goal) / width) {}
    double operator()(BoostVertex v) const {
      const int dx = std::abs(static_cast<int>(v) % width_ - gx_);
      const int dy = std::abs(static_cast<int>(v) / width_ - gy_);
      const int lo = dx < dy ? dx : dy;
      const int hi = dx < dy ? dy : dx;
      return static_cast<double>(hi - lo) + std::sqrt(2.0) * static_cast<double>(lo);
    }

   private:
    int width_, gx_, gy_;
  };

  const BoostGridGraph& g_;
  int width_;
  std::vector<BoostVertex> predecessor_;
  std::vector<double> distance_;
  std::vector<double> rank_;
  std::vector<boost::default_color_type> color_;
};

}  // namespace rtfuse::test
