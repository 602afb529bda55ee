#pragma once
// The simulated base of a commanded drive ([drive] mode = "commanded"): its
// ground truth is not scripted but integrated from the velocity commands
// the runtime sends (rtfuse/cmd_vel), through the drive's kinematics.
//
// Commands go into one CommandFeed (single producer: whoever delivers
// cmd_vel). Every thread that reads truth (each simulated device's driver
// thread, the drive) owns a CommandedTruth that integrates the same feed
// from its own state, lazily, up to the time it asks for. No locks and no
// shared mutable state between readers: only the feed's lock-free slots.
//
// Determinism: a command issued at T acts from the first 1 ms step at or
// after T + command_latency_s. In lockstep the runtime issues commands at
// the tick (T) and no device reads truth beyond the tick before the next
// one, so every command is in the feed before any reader integrates its
// effect step: all readers then take the same steps with the same
// commands and agree bit for bit, whatever times each of them asks for. A
// command that arrives after a reader has already integrated past its
// effect time (live, or a latency shorter than the delivery) acts on that
// reader's next step instead and is counted (late_commands): a non-zero
// count says the run was not deterministic.
//
// The model, per 1 ms step: the command in effect (v, w) asks each side for
// v -/+ w * track / 2 (skid steer: both wheels of a side, effective track),
// clamped to +-max_wheel_speed, and each side's speed moves towards it by at
// most max_wheel_accel * 1 ms; the body's (v, w) follow from the two sides,
// and the pose advances exactly along the arc (or line) of that constant
// (v, w). Between steps the state is the last step's advanced along the
// same arc, so truth_at() is continuous and exact for the model. The
// reported accelerations are the step's change of speed over the step.
// Watchdog: when the newest command in effect has been in effect for more
// than command_timeout_s, the wheels' target becomes zero (counted once per
// stop, when that command was not a stop itself). Wheels roll the ground speed of their side plus slip: the
// scenario's [slip] (wheel_slip_model.hpp), the continuous fraction
// integrated by the trapezoid rule over each step.
#include <atomic>
#include <cstdint>
#include <memory>

#include "core/time.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/truth_source.hpp"
#include "sim/wheel_slip_model.hpp"

namespace rtfuse::sim {

// A velocity command as the base receives it (geometry_msgs/Twist's
// linear.x and angular.z).
struct BaseCommand {
  TimeNs issued = 0;     // when it was sent, on the robot's clock
  double linear = 0.0;   // m/s, forward
  double angular = 0.0;  // rad/s, positive turns left
};

// Append-only ring of commands: one producer, any number of readers, each
// with its own cursor. A slot is a small seqlock of atomic words, so a
// reader that is lapped sees that its command was overwritten rather than
// read half of another one. Allocates once, at construction.
class CommandFeed {
 public:
  // 16384 commands: 164 s at 100 Hz, which a reader of a running device
  // never lags by (the slowest, the GNSS, reads every 0.2 s).
  static constexpr std::uint64_t kCapacity = std::uint64_t{1} << 14;

  CommandFeed();
  ~CommandFeed();
  CommandFeed(const CommandFeed&) = delete;
  CommandFeed& operator=(const CommandFeed&) = delete;

  // Producer only. A command issued before the newest accepted one is
  // refused (false, counted): a base acts on commands in the order they
  // were sent. A non-finite speed is counted and stored as 0 (a stop).
  bool push(const BaseCommand& command) noexcept;

  // Any thread. Commands accepted so far; command i < published() is
  // complete in the feed (acquire).
  std::uint64_t published() const noexcept { return count_.load(std::memory_order_acquire); }
  // Command number i; false when it is not published or already overwritten.
  bool read(std::uint64_t i, BaseCommand* out) const noexcept;
  std::int64_t rejected_out_of_order() const noexcept { return rejected_.load(std::memory_order_relaxed); }
  std::int64_t non_finite() const noexcept { return non_finite_.load(std::memory_order_relaxed); }

 private:
  struct Slot;
  std::unique_ptr<Slot[]> slots_;
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> rejected_{0};
  std::atomic<std::int64_t> non_finite_{0};
  TimeNs last_issued_;  // the producer's own
};

// One reader's commanded truth. Not thread-safe: one thread per instance
// (truth_source.hpp); the counters may be read from any thread.
class CommandedTruth final : public TruthSource {
 public:
  static constexpr TimeNs kStepNs = 1'000'000;
  // Whole steps kept for queries earlier than the newest step: 256 ms.
  static constexpr int kHistorySteps = 256;
  // Steps one query integrates at most (10 minutes); a query further ahead
  // is answered at that step and counted, and the next one goes on from it.
  static constexpr std::int64_t kMaxStepsPerQuery = 600'000;

  // scenario: [robot] and [base]; slip: the scenario's, shared by every
  // reader; t0: the instant the drive starts (the devices' t0), against
  // which the commands' issue times count. All must outlive this.
  CommandedTruth(const DriveScenario& scenario, const WheelSlipModel& slip, const CommandFeed& feed, TimeNs t0);

  // t_s: seconds since t0. Integrates forward to t_s as needed; an earlier
  // time within the history is answered from it, before it from the oldest
  // step kept (counted, with .t that step's time). Before the start: at
  // rest at the origin. Never allocates; at most kMaxStepsPerQuery steps.
  TruthState truth_at(double t_s) noexcept override;

  // The newest step integrated, -1 before the first query.
  std::int64_t last_step() const noexcept { return last_; }

  // Commands that arrived after this reader had integrated past their
  // effect time (each applied at its next step instead).
  std::int64_t late_commands() const noexcept { return late_.load(std::memory_order_relaxed); }
  // Commands lost because the feed overwrote them before this reader got to them.
  std::int64_t feed_overruns() const noexcept { return overruns_.load(std::memory_order_relaxed); }
  // Queries earlier than the history, answered from its oldest step.
  std::int64_t history_misses() const noexcept { return history_misses_.load(std::memory_order_relaxed); }
  // Queries beyond kMaxStepsPerQuery, answered at that step.
  std::int64_t far_queries() const noexcept { return far_queries_.load(std::memory_order_relaxed); }
  // Times the base's watchdog stopped it (no new command for
  // command_timeout_s while the last one asked for motion).
  std::int64_t watchdog_stops() const noexcept { return watchdog_stops_.load(std::memory_order_relaxed); }

 private:
  // One whole step: the state at its start and what is constant during it.
  struct Step {
    std::int64_t k = 0;
    double x = 0.0, y = 0.0, heading = 0.0, distance = 0.0;
    double v = 0.0, w = 0.0;                  // body, during the step
    double accel = 0.0, yaw_accel = 0.0;      // the change from the step before, per second
    double side[2] = {0.0, 0.0};              // [left, right] ground speed of the wheels
    double wheel_distance[kMaxSimWheels] = {};
    double noise_start[kMaxSimWheels] = {};   // continuous slip fraction at the step's start
  };

  void first_step() noexcept;
  void advance_to(std::int64_t k) noexcept;
  // Velocities of step n.k from the commands in effect then and `prev`.
  void decide(Step& n, const Step& prev) noexcept;
  bool fetch_command() noexcept;
  // The state tau_ns into step s.
  void evolve(const Step& s, TimeNs tau_ns, TruthState* out) const noexcept;

  const WheelSlipModel& slip_;
  const CommandFeed& feed_;
  TimeNs t0_;
  int wheel_count_ = 0;
  bool wheel_left_[kMaxSimWheels] = {};
  double track_ = 0.5;
  double max_speed_ = 1.0;
  double max_delta_ = 0.001;  // speed change per step
  TimeNs latency_ns_ = 0;
  TimeNs timeout_ns_ = 0;

  Step steps_[kHistorySteps];  // step k at k % kHistorySteps
  std::int64_t last_ = -1;

  std::uint64_t cursor_ = 0;     // the next command to fetch
  std::uint64_t published_ = 0;  // the feed's count when last looked at
  bool has_pending_ = false;     // fetched, not yet in effect
  BaseCommand pending_;
  TimeNs pending_effect_ns_ = 0;  // since t0
  std::int64_t pending_step_ = 0;
  bool has_command_ = false;
  BaseCommand command_;           // the newest in effect
  TimeNs command_effect_ns_ = 0;
  bool watchdog_stopped_ = false;

  std::atomic<std::int64_t> late_{0};
  std::atomic<std::int64_t> overruns_{0};
  std::atomic<std::int64_t> history_misses_{0};
  std::atomic<std::int64_t> far_queries_{0};
  std::atomic<std::int64_t> watchdog_stops_{0};
};

}  // namespace rtfuse::sim
