#include "navigation/command_gate.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtfuse::navigation {

namespace {

// Whether a stamp is within timeout of now either way. Stamps come from
// other threads and, in a bad case, from garbage: a difference that
// overflows is as untrustworthy as one that is too large.
bool gate_fresh(TimeNs now, TimeNs stamp, TimeNs timeout) noexcept {
  TimeNs age = 0;
  if (__builtin_sub_overflow(now, stamp, &age)) return false;
  return age <= timeout && age >= -timeout;
}

}  // namespace

CommandGate::CommandGate(const FollowerParams& params) : params_(params) {
  std::string error;
  if (!params.check(&error)) throw std::invalid_argument("command gate: " + error);
  period_ns_ = std::max<TimeNs>(1, sec_to_ns(1.0 / params.command_rate_hz));
  estimate_timeout_ns_ = sec_to_ns(params.estimate_timeout_s);
  map_timeout_ns_ = sec_to_ns(params.map_timeout_s);
}

StopReason CommandGate::decide(const GateInput& in, Velocity2 desired) const noexcept {
  if (!in.enabled) return StopReason::kDisabled;
  if (in.stop_requested) return StopReason::kStopCommand;
  if (!in.estimate_finite) return StopReason::kBadPose;
  if (!gate_fresh(in.now, in.estimate_stamp, estimate_timeout_ns_)) return StopReason::kStaleEstimate;
  if (in.map_stamp == 0 || !gate_fresh(in.now, in.map_stamp, map_timeout_ns_)) return StopReason::kStaleMap;
  if (!in.have_goal) return StopReason::kNoGoal;
  if (in.goal_reached) return StopReason::kGoalReached;
  if (!in.have_path) return StopReason::kNoPath;
  if (in.path_blocked) return StopReason::kPathBlocked;
  if (!finite(desired)) return StopReason::kBadCommand;
  return StopReason::kNone;
}

GateOutput CommandGate::step(const GateInput& in, Velocity2 desired) noexcept {
  GateOutput out;
  out.reason = decide(in, desired);
  double dt = ns_to_sec(period_ns_);
  TimeNs elapsed = 0;
  if (have_last_ && !__builtin_sub_overflow(in.now, last_now_, &elapsed) && elapsed > 0 &&
      elapsed <= 2 * period_ns_) {
    dt = ns_to_sec(elapsed);
  }
  have_last_ = true;
  last_now_ = in.now;
  ++steps_;
  ++counts_[static_cast<std::size_t>(out.reason)];
  last_reason_ = out.reason;
  if (out.reason != StopReason::kNone) {
    last_command_ = Velocity2{};
    return out;  // zero, now
  }

  const double v_max = params_.max_linear_mps;
  const double w_max = params_.max_angular_rps;
  const double v_want = std::clamp(desired.linear, 0.0, v_max);
  const double w_want = std::clamp(desired.angular, -w_max, w_max);
  const Velocity2 last = last_command_;
  const double v = v_want > last.linear ? std::min(v_want, last.linear + params_.max_linear_accel_mps2 * dt)
                                        : std::max(v_want, last.linear - params_.max_linear_decel_mps2 * dt);
  const double dw = params_.max_angular_accel_rps2 * dt;
  const double w = std::clamp(w_want, last.angular - dw, last.angular + dw);
  out.command = Velocity2{std::clamp(v, 0.0, v_max), std::clamp(w, -w_max, w_max)};
  out.dt_s = dt;
  last_command_ = out.command;
  return out;
}

std::uint64_t CommandGate::count(StopReason reason) const noexcept {
  const auto i = static_cast<std::size_t>(reason);
  return i < counts_.size() ? counts_[i] : 0;
}

void CommandGate::restart() noexcept {
  have_last_ = false;
  last_now_ = 0;
  last_command_ = Velocity2{};
  last_reason_ = StopReason::kNone;
}

}  // namespace rtfuse::navigation
