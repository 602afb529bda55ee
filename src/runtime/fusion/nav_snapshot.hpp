#pragma once
// The navigator's part of the loop's snapshot: the command of this tick
// and why, for the publisher (cmd_vel and nav_status are estimate outputs,
// decided on tick time, recorded and compared in a replay like odometry).
// Plain values only: the snapshot crosses threads through a seqlock.
#include <cstdint>

namespace rtfuse {

enum class GoalState : std::uint8_t { kNone, kActive, kReached, kRejected, kCancelled };

inline const char* to_string(GoalState s) noexcept {
  switch (s) {
    case GoalState::kNone: return "none";
    case GoalState::kActive: return "active";
    case GoalState::kReached: return "reached";
    case GoalState::kRejected: return "rejected";
    case GoalState::kCancelled: return "cancelled";
  }
  return "none";
}

struct NavSnapshot {
  bool active = false;        // a navigator runs
  bool command_due = false;   // this tick is a command period's: nav_status goes out
  bool send_command = false;  // and so does cmd_vel (the follower is on, or a goal came while it is off: zero)
  double linear_mps = 0.0;
  double angular_rps = 0.0;
  std::uint8_t stop_reason = 0;  // navigation::StopReason
  std::int32_t goal_seq = 0;
  double goal_x = 0.0, goal_y = 0.0;
  GoalState goal_state = GoalState::kNone;
  char goal_error[64] = {};
  std::int32_t plan_seq = 0;
  std::int32_t path_points = 0;
  double remaining_m = 0.0;
  double cross_track_m = 0.0;
  std::int64_t plans = 0;
  std::int64_t plan_failures = 0;
  std::int64_t replans_blocked = 0;
  std::int64_t replans_off_path = 0;
};

}  // namespace rtfuse
