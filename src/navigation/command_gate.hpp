#pragma once
// The last step before a velocity command goes to the base, once per
// command period: whether the robot may move at all, and if so the
// follower's command within the speed and acceleration limits.
//
// A stop is decided from the inputs alone, in this order (the first that
// holds is the reason told; each one's condition is in its comment):
//   1. kDisabled       !enabled
//   2. kStopCommand    stop_requested
//   3. kBadPose        !estimate_finite
//   4. kStaleEstimate  now - estimate_stamp > estimate_timeout_s, or the
//                      stamp more than that in the future
//   5. kStaleMap       map_stamp == 0 (none yet), or now - map_stamp >
//                      map_timeout_s, or more than that in the future
//   6. kNoGoal         !have_goal
//   7. kGoalReached    goal_reached
//   8. kNoPath         !have_path
//   9. kPathBlocked    path_blocked
//  10. kBadCommand     the command given is not finite
// The order puts what the operator set first (off, stop), then what makes
// every later check meaningless (no trustworthy pose, no current map),
// then the task's own state. A stop's command is exactly zero on the very
// step its condition appears: it is not ramped down by the deceleration
// limit, because the reasons to stop are the reasons the robot cannot
// tell where it is going (a base that brakes on zero does so within its
// own limits, which is its controller's business, not this loop's).
//
// Driving: linear clamped to [0, max_linear_mps] (never backwards: there is
// no sensor behind), angular to [-max_angular_rps, max_angular_rps], then
// each moved from the last command by at most its acceleration (linear:
// max_linear_accel_mps2 up, max_linear_decel_mps2 down; angular:
// max_angular_accel_rps2 either way) times dt, the time since the last
// step. dt is one nominal period (1 / command_rate_hz) on the first step,
// when now has not advanced, or when it advanced by more than two periods
// (a late step does not earn a larger jump). After a stop the last command
// is zero: the robot accelerates from standstill again.
//
// Pure: time comes in as now; no clock, no I/O, no allocation.
#include <array>
#include <cstdint>

#include "core/time.hpp"
#include "navigation/follower_params.hpp"
#include "navigation/pose2.hpp"
#include "navigation/stop_reason.hpp"

namespace rtfuse::navigation {

struct GateInput {
  TimeNs now = 0;
  bool enabled = false;
  bool have_goal = false;
  bool have_path = false;
  bool goal_reached = false;
  bool stop_requested = false;  // latched by the caller until a new goal
  TimeNs estimate_stamp = 0;    // of the pose the follower used
  bool estimate_finite = false;
  TimeNs map_stamp = 0;         // of the costmap the path was checked on; 0: none yet
  bool path_blocked = false;
};

struct GateOutput {
  Velocity2 command;
  StopReason reason = StopReason::kNone;
  double dt_s = 0.0;  // what the acceleration limits were applied over; 0 when stopped

  bool stopped() const noexcept { return reason != StopReason::kNone; }
};

class CommandGate {
 public:
  // Throws std::invalid_argument when params.check() fails.
  explicit CommandGate(const FollowerParams& params);

  // The command to send now, and why it is zero when it is.
  GateOutput step(const GateInput& in, Velocity2 desired) noexcept;

  // The reason step() would give, without changing anything.
  StopReason decide(const GateInput& in, Velocity2 desired) const noexcept;

  StopReason last_reason() const noexcept { return last_reason_; }
  Velocity2 last_command() const noexcept { return last_command_; }
  // Steps that ended with this reason (kNone: steps that drove).
  std::uint64_t count(StopReason reason) const noexcept;
  std::uint64_t steps() const noexcept { return steps_; }
  // As constructed: no last step, the last command zero; the counts kept.
  void restart() noexcept;
  TimeNs period_ns() const noexcept { return period_ns_; }
  const FollowerParams& params() const noexcept { return params_; }

 private:
  FollowerParams params_;
  TimeNs period_ns_;
  TimeNs estimate_timeout_ns_;
  TimeNs map_timeout_ns_;
  bool have_last_ = false;
  TimeNs last_now_ = 0;
  Velocity2 last_command_;
  StopReason last_reason_ = StopReason::kNone;
  std::uint64_t steps_ = 0;
  std::array<std::uint64_t, kStopReasonCount> counts_{};
};

}  // namespace rtfuse::navigation
