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
// Deterministic: the same grid, cells and parameters give the same path
// on every run and on x86-64 and aarch64: IEEE double operations one at a
// time (the build does not contract multiply-adds), the factors from a
// table made per plan, sqrt(2) a constant. A cell's cost from the start is
// kept as two sums, a of its straight steps' factors and b of its diagonal
// ones, g = a + sqrt(2) b: over free cells a and b are exact integers, so
// equally long routes tie exactly instead of by rounding noise. The open
// list orders by f = g + h, then larger g (of equal-f cells the one nearer
// the goal: on open ground A* walks straight to it), then the smaller cell
// index.
//
// Fixed workspace: everything is allocated by the constructor for grids up
// to max_width x max_height and paths up to max_path_cells; plan()
// allocates nothing and never throws. A search keeps no state between
// plans: a per-cell stamp says which plan last saw the cell, so nothing is
// cleared per plan either.
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
// Weights above this are refused: a route's cost must stay finite.
inline constexpr double kMaxCostWeight = 1.0e6;

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
  // The path's cost in cells (kOk and kPathTooLong; 0 otherwise): its
  // straight steps' factors summed from the start, plus sqrt(2) times its
  // diagonal steps' factors summed from the start. Equal to the sum of the
  // step costs to rounding.
  double cost = 0.0;
  // Cells taken off the open list and expanded (the goal's pop included).
  std::size_t expansions = 0;

  bool ok() const noexcept { return status == PlanStatus::kOk; }
};

class GridPlanner {
 public:
  // Allocates here, never after. Throws std::invalid_argument for a size
  // below 1 or a workspace of 2^31 cells or more.
  GridPlanner(int max_width, int max_height, std::size_t max_path_cells);
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

 private:
  struct Node;
  struct OpenEntry;

  void make_tables(const PlannerParams& params) noexcept;
  template <bool kAStar>
  bool search(const CostView& grid, GridCell start, GridCell goal, PlanResult& result) noexcept;
  void next_stamp() noexcept;
  void push(std::uint32_t cell, double g, double f) noexcept;
  void sift_up(std::uint32_t slot, OpenEntry entry) noexcept;
  OpenEntry pop() noexcept;

  int max_width_;
  int max_height_;
  std::size_t max_path_;
  std::size_t cells_;
  std::unique_ptr<Node[]> nodes_;              // per cell: g, stamp, open-list slot
  std::unique_ptr<std::uint8_t[]> parent_;     // per cell: the step that reached it (0..7)
  std::unique_ptr<OpenEntry[]> open_;          // binary heap, at most one entry per cell
  std::unique_ptr<GridCell[]> path_;
  std::uint32_t open_size_ = 0;
  std::uint32_t stamp_ = 0;
  // Per plan, indexed by cell cost: passable or not, the step factor.
  bool passable_[256] = {};
  double factor_[256] = {};
};

}  // namespace rtfuse::navigation
