#pragma once
// Why the command gate let no motion out this period (kNone: it did). The
// values are fixed: they go into diagnostics and LCM as a byte.
#include <cstdint>

namespace rtfuse::navigation {

enum class StopReason : std::uint8_t {
  kNone = 0,           // driving
  kDisabled = 1,       // the follower is off by configuration
  kNoGoal = 2,         // nothing to go to
  kGoalReached = 3,    // within the goal tolerance of the path's end
  kStaleEstimate = 4,  // the pose estimate is older than estimate_timeout_s (or far in the future)
  kStaleMap = 5,       // no costmap yet, or older than map_timeout_s (or far in the future)
  kPathBlocked = 6,    // the path ahead crosses a lethal, inscribed or unknown cell, or leaves the map
  kStopCommand = 7,    // an operator's stop, latched by the caller until a new goal
  kNoPath = 8,         // a goal but no path: the planner is planning or found none
  kBadPose = 9,        // the pose estimate is not finite
  kBadCommand = 10,    // the follower's command is not finite (a bug, never an input)
};

inline constexpr int kStopReasonCount = 11;

// The short snake_case name diagnostics and LCM carry, never null.
inline const char* to_string(StopReason reason) noexcept {
  switch (reason) {
    case StopReason::kNone: return "none";
    case StopReason::kDisabled: return "disabled";
    case StopReason::kNoGoal: return "no_goal";
    case StopReason::kGoalReached: return "goal_reached";
    case StopReason::kStaleEstimate: return "stale_estimate";
    case StopReason::kStaleMap: return "stale_map";
    case StopReason::kPathBlocked: return "path_blocked";
    case StopReason::kStopCommand: return "stop_command";
    case StopReason::kNoPath: return "no_path";
    case StopReason::kBadPose: return "bad_pose";
    case StopReason::kBadCommand: return "bad_command";
  }
  return "unknown";
}

}  // namespace rtfuse::navigation
