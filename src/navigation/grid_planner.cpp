#include "navigation/grid_planner.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace rtfuse::navigation {

namespace {

constexpr std::uint32_t kClosed = 0xFFFFFFFFu;
constexpr std::size_t kMaxWorkspaceCells = std::size_t{1} << 31;

// The 8 steps: the four orthogonal first (E, N, W, S), then the diagonals
// (NE, NW, SW, SE), each between two of them.
constexpr int kStepX[8] = {1, 0, -1, 0, 1, -1, -1, 1};
constexpr int kStepY[8] = {0, 1, 0, -1, 1, 1, -1, -1};

bool inside(const CostView& grid, GridCell c) noexcept {
  return c.x >= 0 && c.y >= 0 && c.x < grid.width && c.y < grid.height;
}

}  // namespace

// A cell's cost from the start as its two sums: the factors of its
// straight steps (a) and of its diagonal ones (b), g = a + sqrt(2) b. Over
// free cells both are small integers, exact, so routes of equal length
// have equal g and f, and the open list's tie-break (larger g) sees them
// as equal instead of ordering them by rounding noise.
struct GridPlanner::Node {
  double a;
  double b;
  std::uint32_t stamp;  // the plan that last reached the cell; a, b and slot are that plan's
  std::uint32_t slot;   // its place in the open list, or kClosed once expanded
};

struct GridPlanner::OpenEntry {
  double f;
  double g;
  std::uint32_t cell;
};

namespace {

// The open list's order: f, then larger g, then the smaller cell index. A
// total order on distinct cells, so the search is the same on every run.
template <typename Entry>
bool before(const Entry& a, const Entry& b) noexcept {
  if (a.f != b.f) return a.f < b.f;
  if (a.g != b.g) return a.g > b.g;
  return a.cell < b.cell;
}

// f = g + h for a cell reached with sums (a, b) at (x, y): h is the
// octile distance to the goal, the cost of the cheapest route on an empty
// grid (every factor 1), hi - lo straight steps and lo diagonal ones,
// added to a and b before sqrt(2) multiplies. Dijkstra's h is 0.
template <bool kAStar>
double f_of(double a, double b, int x, int y, int gx, int gy) noexcept {
  if constexpr (kAStar) {
    const int dx = std::abs(x - gx);
    const int dy = std::abs(y - gy);
    const int lo = dx < dy ? dx : dy;
    const int hi = dx < dy ? dy : dx;
    return (a + static_cast<double>(hi - lo)) + kSqrt2 * (b + static_cast<double>(lo));
  } else {
    static_cast<void>(x);
    static_cast<void>(y);
    static_cast<void>(gx);
    static_cast<void>(gy);
    return a + kSqrt2 * b;
  }
}

}  // namespace

double step_factor(std::uint8_t cost, double cost_weight) noexcept {
  const double c = cost == kCostUnknown ? 0.0 : static_cast<double>(cost);
  return 1.0 + cost_weight * c / 252.0;
}

GridPlanner::GridPlanner(int max_width, int max_height, std::size_t max_path_cells)
    : max_width_(max_width), max_height_(max_height), max_path_(max_path_cells) {
  if (max_width < 1 || max_height < 1 || max_path_cells < 1) {
    throw std::invalid_argument("grid planner: workspace of " + std::to_string(max_width) + " x " +
                                std::to_string(max_height) + " cells and a path of " + std::to_string(max_path_cells) +
                                " cells: each must be at least 1");
  }
  cells_ = static_cast<std::size_t>(max_width) * static_cast<std::size_t>(max_height);
  if (cells_ >= kMaxWorkspaceCells) {
    throw std::invalid_argument("grid planner: workspace of " + std::to_string(cells_) +
                                " cells: at most 2^31 - 1");
  }
  nodes_.reset(new Node[cells_]);
  for (std::size_t i = 0; i < cells_; ++i) nodes_[i] = Node{0.0, 0.0, 0, kClosed};
  parent_.reset(new std::uint8_t[cells_]());
  open_.reset(new OpenEntry[cells_]);
  path_.reset(new GridCell[max_path_]);
}

GridPlanner::~GridPlanner() = default;

std::size_t GridPlanner::workspace_bytes() const noexcept {
  return cells_ * (sizeof(Node) + sizeof(std::uint8_t) + sizeof(OpenEntry)) + max_path_ * sizeof(GridCell);
}

void GridPlanner::make_tables(const PlannerParams& params) noexcept {
  for (int c = 0; c < 256; ++c) {
    const auto cost = static_cast<std::uint8_t>(c);
    passable_[c] = params.passability.passable(cost);
    factor_[c] = step_factor(cost, params.cost_weight);
  }
}

void GridPlanner::next_stamp() noexcept {
  if (++stamp_ == 0) {  // after 2^32 - 1 plans: once, forget every stamp
    for (std::size_t i = 0; i < cells_; ++i) nodes_[i].stamp = 0;
    stamp_ = 1;
  }
}

void GridPlanner::sift_up(std::uint32_t slot, OpenEntry entry) noexcept {
  while (slot > 0) {
    const std::uint32_t up = (slot - 1) / 2;
    if (!before(entry, open_[up])) break;
    open_[slot] = open_[up];
    nodes_[open_[slot].cell].slot = slot;
    slot = up;
  }
  open_[slot] = entry;
  nodes_[entry.cell].slot = slot;
}

void GridPlanner::push(std::uint32_t cell, double g, double f) noexcept {
  sift_up(open_size_++, OpenEntry{f, g, cell});
}

GridPlanner::OpenEntry GridPlanner::pop() noexcept {
  const OpenEntry top = open_[0];
  nodes_[top.cell].slot = kClosed;
  const std::uint32_t size = --open_size_;
  if (size > 0) {
    const OpenEntry last = open_[size];
    std::uint32_t slot = 0;
    for (;;) {
      std::uint32_t child = 2 * slot + 1;
      if (child >= size) break;
      if (child + 1 < size && before(open_[child + 1], open_[child])) ++child;
      if (!before(open_[child], last)) break;
      open_[slot] = open_[child];
      nodes_[open_[slot].cell].slot = slot;
      slot = child;
    }
    open_[slot] = last;
    nodes_[last.cell].slot = slot;
  }
  return top;
}

// The search itself, A* (the octile heuristic) or Dijkstra (none). Returns
// whether the goal was reached; its g and the parents then hold the path.
template <bool kAStar>
bool GridPlanner::search(const CostView& grid, GridCell start, GridCell goal, PlanResult& result) noexcept {
  const int width = grid.width;
  const int height = grid.height;
  const std::uint8_t* const cost = grid.cost;
  const int gx = goal.x;
  const int gy = goal.y;
  const auto goal_index = static_cast<std::uint32_t>(gy * width + gx);
  const auto relax = [this, gx, gy](std::uint32_t v, int x, int y, double a, double b, std::uint8_t step) noexcept {
    Node& node = nodes_[v];
    const double g = a + kSqrt2 * b;
    if (node.stamp != stamp_) {
      node.stamp = stamp_;
      node.a = a;
      node.b = b;
      parent_[v] = step;
      push(v, g, f_of<kAStar>(a, b, x, y, gx, gy));
    } else if (node.slot != kClosed && g < node.a + kSqrt2 * node.b) {
      node.a = a;
      node.b = b;
      parent_[v] = step;
      sift_up(node.slot, OpenEntry{f_of<kAStar>(a, b, x, y, gx, gy), g, v});
    }
  };

  open_size_ = 0;
  const auto start_index = static_cast<std::uint32_t>(start.y * width + start.x);
  nodes_[start_index].stamp = stamp_;
  nodes_[start_index].a = 0.0;
  nodes_[start_index].b = 0.0;
  push(start_index, 0.0, f_of<kAStar>(0.0, 0.0, start.x, start.y, gx, gy));
  const auto row = static_cast<std::uint32_t>(width);
  std::size_t expansions = 0;
  while (open_size_ > 0) {
    const std::uint32_t u = pop().cell;
    ++expansions;
    if (u == goal_index) {
      result.expansions = expansions;
      return true;
    }
    const int y = static_cast<int>(u / row);
    const int x = static_cast<int>(u - static_cast<std::uint32_t>(y) * row);
    const std::uint8_t* const c = cost + u;
    const double a = nodes_[u].a;
    const double b = nodes_[u].b;
    // The orthogonal neighbours' passability (false outside the grid)
    // decides the diagonals too: no step past a blocked corner.
    const bool east = x + 1 < width && passable_[c[1]];
    const bool north = y + 1 < height && passable_[c[width]];
    const bool west = x > 0 && passable_[c[-1]];
    const bool south = y > 0 && passable_[c[-width]];
    if (east) relax(u + 1, x + 1, y, a + factor_[c[1]], b, 0);
    if (north) relax(u + row, x, y + 1, a + factor_[c[width]], b, 1);
    if (west) relax(u - 1, x - 1, y, a + factor_[c[-1]], b, 2);
    if (south) relax(u - row, x, y - 1, a + factor_[c[-width]], b, 3);
    if (east && north && passable_[c[width + 1]]) relax(u + row + 1, x + 1, y + 1, a, b + factor_[c[width + 1]], 4);
    if (west && north && passable_[c[width - 1]]) relax(u + row - 1, x - 1, y + 1, a, b + factor_[c[width - 1]], 5);
    if (west && south && passable_[c[-width - 1]]) relax(u - row - 1, x - 1, y - 1, a, b + factor_[c[-width - 1]], 6);
    if (east && south && passable_[c[-width + 1]]) relax(u - row + 1, x + 1, y - 1, a, b + factor_[c[-width + 1]], 7);
  }
  result.expansions = expansions;
  return false;
}

PlanResult GridPlanner::plan(const CostView& grid, GridCell start, GridCell goal,
                             const PlannerParams& params) noexcept {
  PlanResult result;
  const double w = params.cost_weight;
  if (!grid.valid() || !params.passability.valid() || !(w >= 0.0 && w <= kMaxCostWeight)) {
    result.status = PlanStatus::kInvalidInput;
    return result;
  }
  if (grid.width > max_width_ || grid.height > max_height_) {
    result.status = PlanStatus::kGridTooLarge;
    return result;
  }
  if (!inside(grid, start)) {
    result.status = PlanStatus::kStartOutsideGrid;
    return result;
  }
  if (!inside(grid, goal)) {
    result.status = PlanStatus::kGoalOutsideGrid;
    return result;
  }
  const Passability& rule = params.passability;
  if (!rule.passable(grid.at(start.x, start.y))) {
    result.status = PlanStatus::kStartBlocked;
    return result;
  }
  const std::uint8_t goal_cost = grid.at(goal.x, goal.y);
  if (!rule.passable(goal_cost)) {
    result.status = goal_cost == kCostUnknown ? PlanStatus::kGoalUnknown : PlanStatus::kGoalInObstacle;
    return result;
  }

  make_tables(params);
  next_stamp();
  const bool found = params.mode == SearchMode::kAStar ? search<true>(grid, start, goal, result)
                                                       : search<false>(grid, start, goal, result);
  if (!found) {
    result.status = PlanStatus::kNoRoute;
    return result;
  }

  // Back from the goal along the steps that reached each cell: count, then
  // write start to goal.
  const int width = grid.width;
  const auto start_index = static_cast<std::uint32_t>(start.y * width + start.x);
  const auto goal_index = static_cast<std::uint32_t>(goal.y * width + goal.x);
  result.cost = nodes_[goal_index].a + kSqrt2 * nodes_[goal_index].b;
  std::size_t cells = 1;
  for (std::uint32_t i = goal_index; i != start_index; ++cells) {
    const std::uint8_t step = parent_[i];
    i = static_cast<std::uint32_t>(static_cast<int>(i) - kStepY[step] * width - kStepX[step]);
  }
  if (cells > max_path_) {
    result.status = PlanStatus::kPathTooLong;
    return result;
  }
  GridCell c = goal;
  for (std::size_t k = cells; k-- > 0;) {
    path_[k] = c;
    if (k == 0) break;
    const std::uint8_t step = parent_[static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width) +
                                      static_cast<std::size_t>(c.x)];
    c.x -= kStepX[step];
    c.y -= kStepY[step];
  }
  result.status = PlanStatus::kOk;
  result.path = path_.get();
  result.path_cells = cells;
  return result;
}

}  // namespace rtfuse::navigation
