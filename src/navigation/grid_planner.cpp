#include "navigation/grid_planner.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace rtfuse::navigation {

namespace {

constexpr int kMaxSide = 65535;                           // a coordinate fits an entry's 16 bits
constexpr std::size_t kMaxCells = std::size_t{1} << 28;  // an entry's index fits 29 bits
constexpr std::uint32_t kNoEntry = 0x1FFFFFFFu;
constexpr std::uint32_t kMaxBuckets = 8192;
constexpr int kFractionBits = 32;
constexpr int kBucketBits = 4;  // buckets 1/16 of a cell wide
// Every f of a search stays below 2^55, so it fits a node's word shifted
// past its four flag bits, and a plan's costs are kept offset by
// (kPlansPerEpoch - plan) * 2^59 (Node).
constexpr double kFixedPointLimit = 3.6e16;
constexpr int kFlagBits = 4;
constexpr std::uint64_t kStepBits = 7;
constexpr std::uint64_t kExpanded = 8;
constexpr std::uint64_t kFlags = 15;
constexpr int kEpochShift = 59;
constexpr std::uint32_t kPlansPerEpoch = 31;
constexpr std::uint64_t kNeverReached = UINT64_MAX;

// The 8 steps: the four orthogonal first (E, N, W, S), then the diagonals
// (NE, NW, SW, SE), each between two of them.
constexpr int kStepX[8] = {1, 0, -1, 0, 1, -1, -1, 1};
constexpr int kStepY[8] = {0, 1, 0, -1, 1, 1, -1, -1};

bool inside(const CostView& grid, GridCell c) noexcept {
  return c.x >= 0 && c.y >= 0 && c.x < grid.width && c.y < grid.height;
}

}  // namespace

// A cell's state in one word: its cost from the start (fixed point)
// shifted past four flags and offset by the plan's epoch base, whether it
// has been expanded at that cost, and the step that reached it. The base
// falls by 2^59 from one plan to the next while every shifted cost stays
// below 2^59, so a cell last reached in an earlier plan holds more than
// any cost of this one: "not reached yet" and "reached at a higher cost"
// are one compare, and nothing is cleared between plans but once every 31
// plans. Eight bytes a cell: an expansion's three rows of neighbours touch
// half the cache lines sixteen did.
struct GridPlanner::Node {
  std::uint64_t v;  // base + (g << 4) | expanded << 3 | step

  std::uint32_t step() const noexcept { return static_cast<std::uint32_t>(v & kStepBits); }
};

// An open-list entry: the cell (x in the low 16 bits, y in the high) and
// the next entry of its bucket. Its f is not kept: the bucket says enough.
struct GridPlanner::Entry {
  std::uint32_t xy;
  std::uint32_t next;
};

double step_factor(std::uint8_t cost, double cost_weight) noexcept {
  const double c = cost == kCostUnknown ? 0.0 : static_cast<double>(cost);
  return 1.0 + cost_weight * c / 252.0;
}

GridPlanner::GridPlanner(int max_width, int max_height, std::size_t max_path_cells, std::size_t open_entries)
    : max_width_(max_width), max_height_(max_height), max_path_(max_path_cells) {
  if (max_width < 1 || max_height < 1 || max_width > kMaxSide || max_height > kMaxSide || max_path_cells < 1) {
    throw std::invalid_argument("grid planner: workspace of " + std::to_string(max_width) + " x " +
                                std::to_string(max_height) + " cells and a path of " + std::to_string(max_path_cells) +
                                " cells: sides must be in [1, 65535], the path at least 1");
  }
  cells_ = static_cast<std::size_t>(max_width) * static_cast<std::size_t>(max_height);
  if (cells_ >= kMaxCells) {
    throw std::invalid_argument("grid planner: workspace of " + std::to_string(cells_) + " cells: at most 2^28 - 1");
  }
  pool_size_ = open_entries == 0 ? 2 * cells_ : open_entries;
  if (pool_size_ >= kNoEntry) {
    throw std::invalid_argument("grid planner: an open list of " + std::to_string(pool_size_) +
                                " entries: at most 2^29 - 2");
  }
  nodes_.reset(new Node[cells_]);
  for (std::size_t i = 0; i < cells_; ++i) nodes_[i] = Node{kNeverReached};
  pool_.reset(new Entry[pool_size_]);
  head_.reset(new std::uint32_t[kMaxBuckets]);
  path_.reset(new GridCell[max_path_]);
}

GridPlanner::~GridPlanner() = default;

std::size_t GridPlanner::workspace_bytes() const noexcept {
  return cells_ * sizeof(Node) + pool_size_ * sizeof(Entry) + kMaxBuckets * sizeof(std::uint32_t) +
         max_path_ * sizeof(GridCell);
}

void GridPlanner::make_tables(const PlannerParams& params, std::size_t cells) noexcept {
  double most = 1.0;  // the largest factor of a passable cell
  for (int c = 0; c < 256; ++c) {
    const auto cost = static_cast<std::uint8_t>(c);
    passable_[c] = params.passability.passable(cost);
    factor_[c] = step_factor(cost, params.cost_weight);
    if (passable_[c] && factor_[c] > most) most = factor_[c];
  }
  // A route visits each cell once at most, h is at most the grid's
  // octile diameter: f < 2 sqrt(2) most cells in cells, kept under 2^55
  // (a node holds it shifted past its four flags, under 2^59).
  int bits = kFractionBits;
  while (bits > 0 && std::ldexp(2.0 * kSqrt2 * most * static_cast<double>(cells + 2), bits) > kFixedPointLimit) --bits;
  fraction_bits_ = bits;
  for (int c = 0; c < 256; ++c) {
    straight_[c] = std::llround(std::ldexp(factor_[c], bits));
    diagonal_[c] = std::llround(std::ldexp(kSqrt2 * factor_[c], bits));
  }
  // An entry's f is at most two of the largest diagonal steps above the f
  // of the cell that entered it, itself in the lowest bucket: the buckets
  // in use span that much, and wider buckets keep their number bounded.
  const double spread = 2.0 * kSqrt2 * most + 1.0;
  int shift = bits - kBucketBits;
  if (shift < 0) shift = 0;
  while (std::ldexp(spread, bits - shift) > static_cast<double>(kMaxBuckets - 4)) ++shift;
  bucket_shift_ = shift;
  buckets_ = 16;
  while (static_cast<double>(buckets_) < std::ldexp(spread, bits - shift) + 4.0) buckets_ *= 2;
}

void GridPlanner::next_plan() noexcept {
  if (++plan_ > kPlansPerEpoch) {  // the bases are used up: forget every cost
    for (std::size_t i = 0; i < cells_; ++i) nodes_[i].v = kNeverReached;
    plan_ = 1;
  }
}

std::uint64_t GridPlanner::base() const noexcept {
  return static_cast<std::uint64_t>(kPlansPerEpoch - plan_) << kEpochShift;
}

// What compact() leaves: the free entries' list.
struct GridPlanner::Compacted {
  std::uint32_t free_list;
};

// Drops the entries the search no longer needs (those of cells expanded
// at their cost, and all but the first of a cell's others) from the
// buckets to the free list. Buckets are walked from the one being taken
// and each from its newest entry, so the entry kept is the cell's
// cheapest: the one the search would take. The expanded flag marks a cell
// whose entry is kept during the walk, and is cleared again after it. At
// most one entry per cell is left, so a pool 8 larger than the grid
// always gains room for an expansion; a smaller one may not, and the
// search then ends (kOpenListFull). Takes and returns values, so that the
// search's counters stay in registers (their addresses never taken).
GridPlanner::Compacted GridPlanner::compact(std::uint32_t row, std::uint32_t buckets, std::uint32_t first,
                                            std::uint32_t free_list) noexcept {
  ++compactions_;
  Entry* const pool = pool_.get();
  Node* const nodes = nodes_.get();
  const auto node_of = [&](const Entry& e) -> Node& { return nodes[(e.xy >> 16) * row + (e.xy & 0xFFFFu)]; };
  for (std::uint32_t k = 0; k < buckets; ++k) {
    std::uint32_t* link = &head_[(first + k) & (buckets - 1)];
    while (*link != kNoEntry) {
      const std::uint32_t idx = *link;
      Entry& e = pool[idx];
      Node& n = node_of(e);
      if ((n.v & kExpanded) == 0) {
        n.v |= kExpanded;
        link = &e.next;
      } else {
        *link = e.next;
        e.next = free_list;
        free_list = idx;
      }
    }
  }
  for (std::uint32_t b = 0; b < buckets; ++b) {
    for (std::uint32_t idx = head_[b]; idx != kNoEntry; idx = pool[idx].next) node_of(pool[idx]).v &= ~kExpanded;
  }
  return Compacted{free_list};
}

// The search: A* (the octile heuristic) or Dijkstra (none), with reopening
// over the bucket queue. Returns whether the goal was reached; the cells'
// steps then lead back from it. Everything it changes per step is a local
// whose address is never taken: stores through the pools' pointers could
// otherwise alias it and force it back to memory at every step.
template <bool kAStar>
bool GridPlanner::search(const CostView& grid, GridCell start, GridCell goal, PlanResult& result) noexcept {
  const int width = grid.width;
  const int height = grid.height;
  const std::uint8_t* const cost = grid.cost;
  const int gx = goal.x;
  const int gy = goal.y;
  const auto row = static_cast<std::uint32_t>(width);
  const std::ptrdiff_t w = width;  // a row's stride, in cells and in nodes
  const std::uint32_t goal_index = static_cast<std::uint32_t>(gy) * row + static_cast<std::uint32_t>(gx);
  // The octile distance in the fixed point, from a cell's offset to the
  // goal: hi - lo straight steps and lo diagonal ones of factor 1, each the
  // same integer a step's cost is (hi times the one, lo times the other's
  // excess over it: the same sum).
  const std::uint64_t unit = static_cast<std::uint64_t>(straight_[kCostFree]) << kFlagBits;
  const std::uint64_t diagonal_excess = (static_cast<std::uint64_t>(diagonal_[kCostFree]) << kFlagBits) - unit;
  const auto h_of = [=](int dx, int dy) noexcept -> std::uint64_t {
    if constexpr (kAStar) {
      dx = std::abs(dx);
      dy = std::abs(dy);
      const int lo = dx < dy ? dx : dy;
      const int hi = dx < dy ? dy : dx;
      return static_cast<std::uint64_t>(hi) * unit + static_cast<std::uint64_t>(lo) * diagonal_excess;
    } else {
      static_cast<void>(dx);
      static_cast<void>(dy);
      return 0;
    }
  };
  // The steps' costs shifted as a node holds them.
  bool passable[256];
  std::uint64_t straight[256];
  std::uint64_t diagonal[256];
  for (int c = 0; c < 256; ++c) {
    passable[c] = passable_[c];
    straight[c] = static_cast<std::uint64_t>(straight_[c]) << kFlagBits;
    diagonal[c] = static_cast<std::uint64_t>(diagonal_[c]) << kFlagBits;
  }
  Node* const nodes = nodes_.get();
  Entry* const pool = pool_.get();
  std::uint32_t* const head = head_.get();
  const auto pool_size = static_cast<std::uint32_t>(pool_size_);
  const std::uint32_t buckets = buckets_;
  const std::uint32_t mask = buckets - 1;
  const int shift = bucket_shift_ + kFlagBits;
  const std::uint64_t g0 = base();                      // costs are kept offset by it
  const std::uint64_t f0 = g0 + h_of(start.x - gx, start.y - gy);  // bucket 0 begins at the start's f
  for (std::uint32_t k = 0; k < buckets; ++k) head[k] = kNoEntry;
  std::uint64_t current = 0;  // the bucket being taken, counted from bucket 0 (not modulo)
  std::uint32_t free_list = kNoEntry;
  std::uint32_t unused = 0;  // entries never used yet start here
  bool full = false;         // an open list smaller than the grid held only needed entries
  // The goal's node holds its cost so far, an upper bound: buckets
  // starting at or above it and entries whose f reaches it cannot lead to
  // a cheaper route, the former are not taken, the latter not expanded.
  // Read where it decides, never tracked: a relaxation only writes nodes.
  // Until the goal is reached in this plan its node holds more than any f
  // (kNeverReached or an earlier plan's cost).
  Node* const goal_node = nodes + goal_index;
  const std::uint64_t this_plan = g0 + (std::uint64_t{1} << kEpochShift);  // every node of this plan is below

  // f never falls along a step (the costs and the heuristic are consistent
  // exactly, in integers) and rises by at most two of the largest steps
  // (make_tables()), so an entry's bucket is never behind the one being
  // taken nor past the window: no clamp. Room for the pushes is made once
  // an expansion, so a push never checks for it.
  const auto push = [&](std::uint32_t xy, std::uint64_t f) noexcept {
    const auto slot = static_cast<std::uint32_t>((f - f0) >> shift) & mask;
    std::uint32_t idx = free_list;
    if (idx != kNoEntry) {
      free_list = pool[idx].next;
    } else {
      idx = unused++;
    }
    pool[idx] = Entry{xy, head[slot]};
    head[slot] = idx;
  };
  const auto room_for_8 = [&](std::uint32_t list, std::uint32_t used) noexcept {
    std::uint32_t room = pool_size - used;
    for (; list != kNoEntry && room < 8; list = pool[list].next) ++room;
    return room >= 8;
  };
  // A neighbour is its node and its cell packed as an entry holds it (x
  // in the low 16 bits, y in the high: a step adds a constant to it). The
  // goal is entered like any cell.
  // dx, dy: the neighbour's offset to the goal, for its heuristic.
  const auto relax = [&](Node* node, std::uint32_t xy, std::uint64_t g, std::uint64_t step, int dx,
                         int dy) noexcept {
    if ((g | kFlags) >= node->v) return;
    node->v = g | step;
    push(xy, g + h_of(dx, dy));
  };

  const std::uint32_t start_index = static_cast<std::uint32_t>(start.y) * row + static_cast<std::uint32_t>(start.x);
  nodes[start_index].v = g0;
  push(static_cast<std::uint32_t>(start.x) | static_cast<std::uint32_t>(start.y) << 16, f0);
  std::size_t expansions = 0;
  for (;;) {
    std::uint32_t slot = static_cast<std::uint32_t>(current) & mask;
    std::uint32_t idx = head[slot];
    if (idx == kNoEntry) {  // the bucket is done: on to the next one with entries
      std::uint32_t empty = 1;
      do {
        ++current;
        // Stop once a bucket starts at the goal's cost, or when a whole
        // window of buckets is empty: so is the open list.
        if ((current << shift) >= (goal_node->v & ~kFlags) - f0 || empty == buckets) break;
        slot = static_cast<std::uint32_t>(current) & mask;
        idx = head[slot];
        ++empty;
      } while (idx == kNoEntry);
      if (idx == kNoEntry) break;
    }
    const Entry e = pool[idx];
    head[slot] = e.next;
    pool[idx].next = free_list;
    free_list = idx;
    const std::uint32_t xy = e.xy;
    const int x = static_cast<int>(xy & 0xFFFFu);
    const int y = static_cast<int>(xy >> 16);
    const std::uint32_t u = static_cast<std::uint32_t>(y) * row + static_cast<std::uint32_t>(x);
    Node* const np = nodes + u;
    Node& node = *np;
    // A cell already expanded at its cost: this is an older entry of it
    // (its newest, cheaper, is taken first: a lower bucket, or later in
    // the same one).
    const std::uint64_t v = node.v;
    if (v & kExpanded) continue;
    node.v = v | kExpanded;
    const std::uint64_t g = v & ~kFlags;
    // Once the goal has a route, an entry at or above its cost cannot lead
    // to a cheaper one (the goal's own entry among them: it is never
    // expanded).
    const std::uint64_t goal_v = goal_node->v;
    if (goal_v < this_plan && (g + h_of(x - gx, y - gy)) >= (goal_v & ~kFlags)) continue;
    // Room for this expansion's pushes: the entries never used, and near
    // the pool's end the free ones too.
    if (unused + 8 > pool_size && !room_for_8(free_list, unused)) {
      const Compacted left = compact(row, buckets, static_cast<std::uint32_t>(current) & mask, free_list);
      free_list = left.free_list;
      if (!room_for_8(free_list, unused)) {
        full = true;
        break;
      }
    }
    ++expansions;
    const std::uint8_t* const c = cost + u;
    // The orthogonal neighbours' passability (false outside the grid)
    // decides the diagonals too: no step past a blocked corner.
    const bool east = x + 1 < width && passable[c[1]];
    const bool north = y + 1 < height && passable[c[w]];
    const bool west = x > 0 && passable[c[-1]];
    const bool south = y > 0 && passable[c[-w]];
    const int dx = x - gx;
    const int dy = y - gy;
    if (east) relax(np + 1, xy + 1u, g + straight[c[1]], 0, dx + 1, dy);
    if (north) relax(np + w, xy + 0x10000u, g + straight[c[w]], 1, dx, dy + 1);
    if (west) relax(np - 1, xy - 1u, g + straight[c[-1]], 2, dx - 1, dy);
    if (south) relax(np - w, xy - 0x10000u, g + straight[c[-w]], 3, dx, dy - 1);
    if (east && north && passable[c[w + 1]]) {
      relax(np + w + 1, xy + 0x10001u, g + diagonal[c[w + 1]], 4, dx + 1, dy + 1);
    }
    if (west && north && passable[c[w - 1]]) {
      relax(np + w - 1, xy + 0xFFFFu, g + diagonal[c[w - 1]], 5, dx - 1, dy + 1);
    }
    if (west && south && passable[c[-w - 1]]) {
      relax(np - w - 1, xy - 0x10001u, g + diagonal[c[-w - 1]], 6, dx - 1, dy - 1);
    }
    if (east && south && passable[c[-w + 1]]) {
      relax(np - w + 1, xy - 0xFFFFu, g + diagonal[c[-w + 1]], 7, dx + 1, dy - 1);
    }
  }
  result.expansions = expansions;
  if (full) result.status = PlanStatus::kOpenListFull;
  return !full && goal_node->v < this_plan;
}

PlanResult GridPlanner::plan(const CostView& grid, GridCell start, GridCell goal,
                             const PlannerParams& params) noexcept {
  PlanResult result;
  compactions_ = 0;
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
  std::size_t cells = 1;
  if (start != goal) {
    make_tables(params, static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height));
    next_plan();
    const bool found = params.mode == SearchMode::kAStar ? search<true>(grid, start, goal, result)
                                                         : search<false>(grid, start, goal, result);
    if (!found) {
      if (result.status != PlanStatus::kOpenListFull) result.status = PlanStatus::kNoRoute;
      return result;
    }
    // Back from the goal along the steps that reached each cell: count...
    const auto row = static_cast<std::size_t>(grid.width);
    const auto step_of = [&](GridCell c) {
      return nodes_[static_cast<std::size_t>(c.y) * row + static_cast<std::size_t>(c.x)].step();
    };
    for (GridCell c = goal; c != start; ++cells) {
      const std::uint32_t step = step_of(c);
      c.x -= kStepX[step];
      c.y -= kStepY[step];
    }
    if (cells > max_path_) {
      result.status = PlanStatus::kPathTooLong;
      const auto g = static_cast<std::int64_t>(
          ((nodes_[static_cast<std::size_t>(goal.y) * row + static_cast<std::size_t>(goal.x)].v & ~kFlags) - base()) >>
          kFlagBits);
      result.cost = std::ldexp(static_cast<double>(g), -fraction_bits_);
      return result;
    }
    // ...then write start to goal.
    GridCell c = goal;
    for (std::size_t k = cells - 1; k > 0; --k) {
      path_[k] = c;
      const std::uint32_t step = step_of(c);
      c.x -= kStepX[step];
      c.y -= kStepY[step];
    }
  }
  path_[0] = start;
  // The cost in double, from the path itself.
  double straight = 0.0;
  double diagonal = 0.0;
  for (std::size_t k = 1; k < cells; ++k) {
    const double f = step_factor(grid.at(path_[k].x, path_[k].y), params.cost_weight);
    if (path_[k].x != path_[k - 1].x && path_[k].y != path_[k - 1].y) {
      diagonal = diagonal + f;
    } else {
      straight = straight + f;
    }
  }
  result.cost = straight + kSqrt2 * diagonal;
  result.status = PlanStatus::kOk;
  result.path = path_.get();
  result.path_cells = cells;
  return result;
}

}  // namespace rtfuse::navigation
