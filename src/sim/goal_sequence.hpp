#pragma once
// A commanded drive's goals, given to the navigator one after the other as
// an operator would: the first once the filter runs, each next one when the
// navigator says the last was reached (or refused). The robot's true
// distance to each goal when the navigator called it reached is the
// figure that counts, not the navigator's own belief.
//
// Pure: the drive calls step() after every tick with what the loop
// published and the truth, and sends the goal it is told to.
#include <cstdint>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "runtime/fusion/nav_snapshot.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/truth_source.hpp"

namespace rtfuse::sim {

struct GoalOutcome {
  bool sent = false;
  bool reached = false;   // the navigator said so
  bool rejected = false;  // the navigator refused it
  double truth_error_m = 0.0;  // the robot's true distance to it then
  double sent_s = 0.0;         // since the drive started
  double done_s = 0.0;
  std::string why;  // the navigator's reason when it refused the goal
};

// A goal as an operator's tool sends it: pose_stamped_t in the map's frame
// (`frame`), stamped t. Allocates: a tool's, not the loop's.
std::vector<std::uint8_t> encode_goal(const DriveGoal& goal, const char* frame, TimeNs t);

class GoalSequence {
 public:
  // The goals (none: nothing is ever sent). The first goes out once the
  // estimate is initialised and `settle_s` of the drive have passed: as a
  // robot is left standing at power-up, so the IMU learns its gyro bias at
  // standstill (its 2 s time constant and 0.5 s window) before the first
  // slow turn, which it would otherwise learn as a bias at full pace.
  GoalSequence(const std::vector<DriveGoal>& goals, TimeNs t0, double settle_s = 3.0);

  // After the tick at t: true when a goal is to be sent now (*goal).
  bool step(TimeNs t, bool estimate_initialized, const NavSnapshot& nav, const TruthState& truth,
            DriveGoal* goal) noexcept;

  const std::vector<GoalOutcome>& outcomes() const noexcept { return outcomes_; }
  int reached() const noexcept;
  // The goal in work (== goals sent while one is pending).
  int current() const noexcept { return next_; }

 private:
  std::vector<DriveGoal> goals_;
  std::vector<GoalOutcome> outcomes_;
  TimeNs t0_;
  TimeNs settle_ns_;
  int next_ = 0;           // index of the goal to send next, or in work
  bool waiting_ = false;   // goal next_ was sent; waiting for its outcome
  std::int32_t seq_base_ = -1;  // the navigator's goal_seq before the first goal
};

}  // namespace rtfuse::sim
