#include "navigation/plan_status.hpp"

namespace rtfuse::navigation {

const char* to_string(PlanStatus status) noexcept {
  switch (status) {
    case PlanStatus::kOk: return "ok";
    case PlanStatus::kInvalidInput: return "invalid input";
    case PlanStatus::kGridTooLarge: return "grid larger than the planner's workspace";
    case PlanStatus::kStartOutsideGrid: return "start outside the grid";
    case PlanStatus::kGoalOutsideGrid: return "goal outside the grid";
    case PlanStatus::kStartBlocked: return "start blocked";
    case PlanStatus::kGoalInObstacle: return "goal in an obstacle";
    case PlanStatus::kGoalUnknown: return "goal unknown";
    case PlanStatus::kNoRoute: return "no route";
    case PlanStatus::kPathTooLong: return "path longer than the planner's buffer";
    case PlanStatus::kOpenListFull: return "the planner's open list ran out";
  }
  return "unknown plan status";
}

}  // namespace rtfuse::navigation
