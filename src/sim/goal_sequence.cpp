#include "sim/goal_sequence.hpp"

#include <cmath>

#include "rtfuse/pose_stamped_t.hpp"

namespace rtfuse::sim {

std::vector<std::uint8_t> encode_goal(const DriveGoal& g, const char* frame, TimeNs t) {
  rtfuse::pose_stamped_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = frame;
  m.pose.position.x = g.x_m;
  m.pose.position.y = g.y_m;
  if (g.has_yaw) {
    m.pose.orientation.z = std::sin(0.5 * g.yaw_rad);
    m.pose.orientation.w = std::cos(0.5 * g.yaw_rad);
  }
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

GoalSequence::GoalSequence(const std::vector<DriveGoal>& goals, TimeNs t0, double settle_s)
    : goals_(goals), outcomes_(goals.size()), t0_(t0), settle_ns_(sec_to_ns(settle_s)) {}

bool GoalSequence::step(TimeNs t, bool estimate_initialized, const NavSnapshot& nav, const TruthState& truth,
                        DriveGoal* goal) noexcept {
  const double now_s = ns_to_sec(t - t0_);
  if (waiting_) {
    // The navigator numbers every goal message; ours are the only ones.
    if (nav.goal_seq != seq_base_ + next_ + 1) return false;
    GoalOutcome& o = outcomes_[static_cast<std::size_t>(next_)];
    if (nav.goal_state == GoalState::kReached) {
      o.reached = true;
    } else if (nav.goal_state == GoalState::kRejected) {
      o.rejected = true;
      o.why = nav.goal_error;
    } else {
      return false;
    }
    const DriveGoal& g = goals_[static_cast<std::size_t>(next_)];
    const double dx = truth.x - g.x_m;
    const double dy = truth.y - g.y_m;
    o.truth_error_m = std::sqrt(dx * dx + dy * dy);
    o.done_s = now_s;
    waiting_ = false;
    ++next_;
  }
  if (next_ >= static_cast<int>(goals_.size())) return false;
  if (!estimate_initialized || t - t0_ < settle_ns_) return false;
  if (seq_base_ < 0) seq_base_ = nav.goal_seq;
  GoalOutcome& o = outcomes_[static_cast<std::size_t>(next_)];
  o.sent = true;
  o.sent_s = now_s;
  waiting_ = true;
  *goal = goals_[static_cast<std::size_t>(next_)];
  return true;
}

int GoalSequence::reached() const noexcept {
  int n = 0;
  for (const GoalOutcome& o : outcomes_) n += o.reached ? 1 : 0;
  return n;
}

}  // namespace rtfuse::sim
