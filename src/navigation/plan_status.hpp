#pragma once
// Why a plan was or was not found. A planner never fails any other way: no
// exception, no crash, whatever the input.
#include <cstdint>

namespace rtfuse::navigation {

enum class PlanStatus : std::uint8_t {
  kOk,
  kInvalidInput,       // no grid, a zero size, NaN/negative/huge cost weight, lethal_from outside 1..254
  kGridTooLarge,       // the grid is wider or taller than the planner's workspace
  kStartOutsideGrid,
  kGoalOutsideGrid,
  kStartBlocked,       // the start cell is not passable (obstacle, inscribed, or unknown when that is not)
  kGoalInObstacle,     // the goal's cost is lethal_from or more (inscribed or lethal by default)
  kGoalUnknown,        // the goal is unknown (255) and unknown is not passable
  kNoRoute,            // every cell reachable from the start was searched: the goal is not among them
  kPathTooLong,        // found, but longer than the planner's path buffer (cost and expansions still told)
  kOpenListFull,       // only with an open list made smaller than the grid: it ran out
};

// A short English phrase ("goal in an obstacle"), never null.
const char* to_string(PlanStatus status) noexcept;

}  // namespace rtfuse::navigation
