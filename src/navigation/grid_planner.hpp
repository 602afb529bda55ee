#pragma once
// The optimal path between two cells of a cost grid (issue 28, item 2):
// A* with the octile heuristic, or Dijkstra, on a fixed workspace.
//
// The graph. Nodes are the grid's passable cells (passability.hpp: cost
// below lethal_from, 253 by default; unknown, 255, only when
// unknown_passable). Each is joined to its 8 neighbours that are passable,
// but a diagonal step only when both orthogonal neighbours it passes
// between are passable too: no step cuts an obstacle's corner. A step
// costs its length in cells (1, or sqrt(2) diagonally) times
//   1 + cost_weight * cost / 252
// where cost is the cell stepped into (unknown counts as 0). Every factor
// is at least 1, so the octile distance (the length of the shortest
// 8-connected route on an empty grid) never overestimates the rest of a
// route and grows by at most a step's cost from one cell to the next:
// admissible and consistent, and A* ends with the same optimal cost as
// Dijkstra. With cost_weight 0 (or a grid of only free and lethal cells)
// the graph is the plain one: steps of 1 and sqrt(2). The default weight,
// 2, is Nav2's Smac 2D planner's cost_travel_multiplier, the same term.
//
// The search. Costs are summed in fixed point, 2^-32 of a cell (a step's
// cost rounded once to that, so a route's cost is within 2^-33 of a cell
// per step of its exact value, 1e-10 relative): integer sums are exact
// and associative, so equal routes tie exactly, the heuristic is
// consistent exactly, and the arithmetic is the same on every machine.
// The open list is a bucket queue: f in buckets 1/16 of a cell wide
// (wider for large weights: 8192 buckets at most), taken in order, last
// in first out within a bucket (so on open ground A* walks straight to
// the goal). Within a bucket f is not sorted, so a cell can be expanded
// before its cheapest route is known; it is expanded again when that
// route arrives. The search stops when the lowest bucket left starts at
// or above the goal's cost (every route still open costs at least that):
// the cost is the optimum of the graph, to the fixed point's rounding. A
// push or a pop is O(1) where a binary heap sifts through its levels
// (docs/design.md, "Navigation", "The grid planner", says what that was
// worth). The reported cost is the path's own, in double: the factors of
// its straight steps summed from the start, plus sqrt(2) times those of
// its diagonal steps.
//
// Deterministic: the same grid, cells and parameters give the same path
// and counts on every run and on x86-64 and aarch64: integer search, the
// factors and the reported cost IEEE double operations one at a time (the
// build does not contract multiply-adds), sqrt(2) a constant.
//
// Fixed workspace: everything is allocated by the constructor for grids up
// to max_width x max_height and paths up to max_path_cells; plan()
// allocates nothing and never throws. A search keeps no state between
// plans: each plan's costs are offset by a base that falls from one plan
// to the next, so a cell's cost from an earlier plan reads as "not reached
// yet" and nothing the size of the grid is cleared but once every 31
// plans.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "navigation/cost_values.hpp"
#include "navigation/grid_cell.hpp"
#include "navigation/passability.hpp"
#include "navigation/plan_status.hpp"

namespace rtfuse::navigation {

// sqrt(2) rounded to the nearest double (what std::sqrt(2.0) gives).
inline constexpr double kSqrt2 = 1.4142135623730951;
// Weights above this are refused. The fixed point keeps 32 fraction bits
// unless a route on the grid could then pass 2^55 (weight 2: grids of over
// 980 000 cells; weight 1000: over 2 900), then fewer, 15 at least.
inline constexpr double kMaxCostWeight = 1000.0;

enum class SearchMode : std::uint8_t {
  kAStar,     // octile heuristic: fewer cells expanded
  kDijkstra,  // heuristic 0: the reference, same cost
};

struct PlannerParams {
  Passability passability;
  double cost_weight = 2.0;  // 0..kMaxCostWeight; 0: cost only decides passability
  SearchMode mode = SearchMode::kAStar;
};

// The step cost factor of a cell of cost c (passable): 1 + weight * c / 252,
// unknown as 0. The planner's tables hold exactly these values.
double step_factor(std::uint8_t cost, double cost_weight) noexcept;

struct PlanResult {
  PlanStatus status = PlanStatus::kInvalidInput;
  // Start to goal, each step to one of the 8 neighbours; points into the
  // planner's buffer, valid until its next plan(). Empty unless kOk.
  const GridCell* path = nullptr;
  std::size_t path_cells = 0;
  // The path's cost in cells: its straight steps' factors summed from the
  // start, plus sqrt(2) times its diagonal steps' factors summed from the
  // start, equal to the sum of the step costs to rounding (kOk); the
  // search's fixed-point cost (kPathTooLong); 0 otherwise.
  double cost = 0.0;
  // Cells expanded (their neighbours relaxed), each time it happened: a
  // cell expanded again when a cheaper route to it arrives counts twice.
  // The goal is never expanded; start == goal expands nothing.
  std::size_t expansions = 0;

  bool ok() const noexcept { return status == PlanStatus::kOk; }
};

class GridPlanner {
 public:
  // Allocates here, never after. Throws std::invalid_argument for a size
  // below 1, a side over 65535 cells or a workspace of 2^28 cells or more.
  // open_entries sizes the open list (0: twice the workspace's cells). A
  // search that fills it drops the entries it no longer needs (older
  // entries of cells improved since) and goes on; the list never holds
  // more than one needed entry per cell and an expansion wants room for
  // 8 more, so one 8 larger than the grid never runs out. A smaller one
  // (tests) can: kOpenListFull.
  GridPlanner(int max_width, int max_height, std::size_t max_path_cells, std::size_t open_entries = 0);
  ~GridPlanner();
  GridPlanner(const GridPlanner&) = delete;
  GridPlanner& operator=(const GridPlanner&) = delete;

  // The cheapest path from start to goal on grid, or why there is none.
  // Checks in this order: input, size, start, goal, start passable, goal
  // passable, then searches. start == goal is a path of one cell, cost 0.
  PlanResult plan(const CostView& grid, GridCell start, GridCell goal, const PlannerParams& params) noexcept;

  int max_width() const noexcept { return max_width_; }
  int max_height() const noexcept { return max_height_; }
  std::size_t max_path_cells() const noexcept { return max_path_; }
  // Bytes the workspace holds (for the docs' figures).
  std::size_t workspace_bytes() const noexcept;
  // Times the last plan had to drop dead entries from a full open list.
  std::size_t compactions() const noexcept { return compactions_; }

 private:
  struct Node;
  struct Entry;
  struct Compacted;

  void make_tables(const PlannerParams& params, std::size_t cells) noexcept;
  void next_plan() noexcept;
  std::uint64_t base() const noexcept;
  template <bool kAStar>
  bool search(const CostView& grid, GridCell start, GridCell goal, PlanResult& result) noexcept;
  Compacted compact(std::uint32_t row, std::uint32_t buckets, std::uint32_t first, std::uint32_t free_list) noexcept;

  int max_width_;
  int max_height_;
  std::size_t max_path_;
  std::size_t cells_;
  std::size_t pool_size_;
  std::unique_ptr<Node[]> nodes_;           // per cell: g (offset by the plan's base), expanded, step
  std::unique_ptr<Entry[]> pool_;           // the open list's entries, linked in buckets
  std::unique_ptr<std::uint32_t[]> head_;   // per bucket: its newest entry
  std::unique_ptr<GridCell[]> path_;
  std::uint32_t plan_ = 0;  // 1..31 in an epoch of plans (Node)
  std::size_t compactions_ = 0;
  // Per plan: by cell cost, passable or not, the factor, the straight and
  // diagonal steps in fixed point; the fixed point's fraction bits and the
  // buckets' width (as a shift) and number (a power of two).
  bool passable_[256] = {};
  double factor_[256] = {};
  std::int64_t straight_[256] = {};
  std::int64_t diagonal_[256] = {};
  int fraction_bits_ = 32;
  int bucket_shift_ = 28;
  std::uint32_t buckets_ = 16;
};

}  // namespace rtfuse::navigation
