#include "sim/commanded_base.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "geometry/angles.hpp"

namespace rtfuse::sim {

namespace {

static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "the feed's slots must be lock-free");
static_assert(std::atomic<std::int64_t>::is_always_lock_free, "the counters must be lock-free");

// Doubles travel as their bits: an atomic<double> is not lock-free everywhere.
std::uint64_t command_bits(double v) noexcept {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

double command_value(std::uint64_t b) noexcept {
  double v = 0.0;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

// Owner-only counters: a plain load and store, no read-modify-write, so
// they stay cheap and still readable from another thread.
void bump_counter(std::atomic<std::int64_t>& c, std::int64_t by = 1) noexcept {
  c.store(c.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

// Times since t0 are kept within +-4e18 ns (127 years) so that the
// watchdog's differences of two of them cannot overflow, whatever issue
// times a commander sends.
constexpr TimeNs kCommandTimeLimitNs = 4'000'000'000'000'000'000;

TimeNs command_time_since(TimeNs issued, TimeNs t0) noexcept {
  TimeNs r = 0;
  if (__builtin_sub_overflow(issued, t0, &r)) return issued < t0 ? -kCommandTimeLimitNs : kCommandTimeLimitNs;
  return std::clamp(r, -kCommandTimeLimitNs, kCommandTimeLimitNs);
}

double step_start_s(std::int64_t k) noexcept { return static_cast<double>(k * CommandedTruth::kStepNs) * 1e-9; }

// The side's next speed: towards `target`, by at most max_delta; exactly
// the target once within reach, so a stop ends at 0.0 and not at a residue.
double ramp_wheel(double from, double target, double max_delta) noexcept {
  const double d = target - from;
  if (d > max_delta) return from + max_delta;
  if (d < -max_delta) return from - max_delta;
  return target;
}

}  // namespace

// --- CommandFeed ---------------------------------------------------------------

struct CommandFeed::Slot {
  // i + 1 once command i is complete in the slot; 0 while it is rewritten.
  std::atomic<std::uint64_t> sequence{0};
  std::atomic<std::int64_t> issued{0};
  std::atomic<std::uint64_t> linear{0};
  std::atomic<std::uint64_t> angular{0};
};

CommandFeed::CommandFeed()
    : slots_(std::make_unique<Slot[]>(kCapacity)), last_issued_(std::numeric_limits<TimeNs>::min()) {}

CommandFeed::~CommandFeed() = default;

bool CommandFeed::push(const BaseCommand& command) noexcept {
  if (command.issued < last_issued_) {
    bump_counter(rejected_);
    return false;
  }
  double linear = command.linear;
  double angular = command.angular;
  if (!std::isfinite(linear) || !std::isfinite(angular)) {
    bump_counter(non_finite_);
    linear = 0.0;
    angular = 0.0;
  }
  last_issued_ = command.issued;
  const std::uint64_t i = count_.load(std::memory_order_relaxed);
  Slot& s = slots_[i % kCapacity];
  // Seqlock write: invalidate, then the fields, then the new sequence.
  s.sequence.store(0, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  s.issued.store(command.issued, std::memory_order_relaxed);
  s.linear.store(command_bits(linear), std::memory_order_relaxed);
  s.angular.store(command_bits(angular), std::memory_order_relaxed);
  s.sequence.store(i + 1, std::memory_order_release);
  count_.store(i + 1, std::memory_order_release);
  return true;
}

bool CommandFeed::read(std::uint64_t i, BaseCommand* out) const noexcept {
  const Slot& s = slots_[i % kCapacity];
  if (s.sequence.load(std::memory_order_acquire) != i + 1) return false;
  BaseCommand c;
  c.issued = s.issued.load(std::memory_order_relaxed);
  c.linear = command_value(s.linear.load(std::memory_order_relaxed));
  c.angular = command_value(s.angular.load(std::memory_order_relaxed));
  std::atomic_thread_fence(std::memory_order_acquire);
  // Rewritten meanwhile: what was read may mix two commands.
  if (s.sequence.load(std::memory_order_relaxed) != i + 1) return false;
  *out = c;
  return true;
}

// --- CommandedTruth ------------------------------------------------------------

CommandedTruth::CommandedTruth(const DriveScenario& sc, const WheelSlipModel& slip, const CommandFeed& feed,
                               TimeNs t0)
    : slip_(slip), feed_(feed), t0_(t0) {
  wheel_count_ = std::clamp(sc.robot.wheel_count, 0, kMaxSimWheels);
  for (int w = 0; w < wheel_count_; ++w) wheel_left_[w] = sc.robot.wheels[static_cast<std::size_t>(w)].left;
  track_ = sc.robot.track_width_m;
  max_speed_ = sc.base.max_wheel_speed_mps;
  max_delta_ = sc.base.max_wheel_accel_mps2 * (static_cast<double>(kStepNs) * 1e-9);
  latency_ns_ = sec_to_ns(sc.base.command_latency_s);
  timeout_ns_ = sec_to_ns(sc.base.command_timeout_s);
}

bool CommandedTruth::fetch_command() noexcept {
  if (cursor_ >= published_) {
    published_ = feed_.published();
    if (cursor_ >= published_) return false;
  }
  BaseCommand c;
  // Lapped: skip to the oldest command the feed still holds. Bounded: each
  // try moves the cursor on, and the producer cannot lap it again at once.
  for (int tries = 0; !feed_.read(cursor_, &c); ++tries) {
    if (tries == 4) return false;
    published_ = feed_.published();
    const std::uint64_t oldest = published_ > CommandFeed::kCapacity ? published_ - CommandFeed::kCapacity : 0;
    const std::uint64_t next = std::max(cursor_ + 1, oldest);
    bump_counter(overruns_, static_cast<std::int64_t>(next - cursor_));
    cursor_ = next;
    if (cursor_ >= published_) return false;
  }
  ++cursor_;
  pending_ = c;
  // The base acts on it from the first step at or after issued + latency.
  pending_effect_ns_ = command_time_since(c.issued, t0_) + latency_ns_;
  pending_step_ = pending_effect_ns_ <= 0 ? 0 : pending_effect_ns_ / kStepNs + (pending_effect_ns_ % kStepNs != 0);
  has_pending_ = true;
  return true;
}

void CommandedTruth::decide(Step& n, const Step& prev) noexcept {
  // Every command in effect by this step, the newest winning. One that
  // should have acted on an earlier step arrived after this reader had
  // taken it.
  while (has_pending_ || fetch_command()) {
    if (pending_step_ > n.k) break;
    if (pending_step_ < n.k) bump_counter(late_);
    command_ = pending_;
    command_effect_ns_ = pending_effect_ns_;
    has_command_ = true;
    watchdog_stopped_ = false;
    has_pending_ = false;
  }
  double target[2] = {0.0, 0.0};
  if (has_command_ && !watchdog_stopped_) {
    if (n.k * kStepNs - command_effect_ns_ > timeout_ns_) {
      // The base's own decision: the commander has gone quiet. Counted
      // only when it overrides motion: a commander that sent a stop and
      // then fell silent has lost nothing.
      watchdog_stopped_ = true;
      if (command_.linear != 0.0 || command_.angular != 0.0) bump_counter(watchdog_stops_);
    } else {
      const double turn = command_.angular * (0.5 * track_);
      target[0] = std::clamp(command_.linear - turn, -max_speed_, max_speed_);
      target[1] = std::clamp(command_.linear + turn, -max_speed_, max_speed_);
    }
  }
  for (int side = 0; side < 2; ++side) n.side[side] = ramp_wheel(prev.side[side], target[side], max_delta_);
  n.v = 0.5 * (n.side[0] + n.side[1]);
  n.w = (n.side[1] - n.side[0]) / track_;
  const double per_second = 1e9 / static_cast<double>(kStepNs);
  n.accel = (n.v - prev.v) * per_second;
  n.yaw_accel = (n.w - prev.w) * per_second;
}

void CommandedTruth::first_step() noexcept {
  const Step rest;  // at the origin, wheels still
  Step& s = steps_[0];
  s = rest;
  s.k = 0;
  for (int w = 0; w < wheel_count_; ++w) s.noise_start[w] = slip_.noise_fraction(w, 0.0);
  decide(s, rest);
  last_ = 0;
}

void CommandedTruth::advance_to(std::int64_t k) noexcept {
  if (last_ < 0) first_step();
  while (last_ < k) {
    const Step& s = steps_[last_ % kHistorySteps];
    TruthState end;
    evolve(s, kStepNs, &end);
    Step n;
    n.k = last_ + 1;
    n.x = end.x;
    n.y = end.y;
    n.heading = end.heading;
    n.distance = end.distance;
    const double start = step_start_s(n.k);
    for (int w = 0; w < wheel_count_; ++w) {
      n.wheel_distance[w] = end.wheel_distance[w];
      n.noise_start[w] = slip_.noise_fraction(w, start);
    }
    decide(n, s);
    steps_[n.k % kHistorySteps] = n;
    last_ = n.k;
  }
}

void CommandedTruth::evolve(const Step& s, TimeNs tau_ns, TruthState* out) const noexcept {
  const double tau = static_cast<double>(tau_ns) * 1e-9;
  // Exact for a constant (v, w): the chord of the arc, at the mean heading;
  // sin(h)/h -> 1 makes it the straight line as w -> 0.
  const double half = 0.5 * (s.w * tau);
  const double chord = std::abs(half) < 1e-6 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
  const double along = s.v * tau * chord;
  const double mid = s.heading + half;
  out->x = s.x + along * std::cos(mid);
  out->y = s.y + along * std::sin(mid);
  out->heading = s.heading + s.w * tau;
  out->yaw = geometry::wrap_angle(out->heading);
  out->speed = s.v;
  out->yaw_rate = s.w;
  out->yaw_accel = s.yaw_accel;
  out->accel_body[0] = s.accel;
  out->accel_body[1] = s.v * s.w;
  out->accel_body[2] = 0.0;
  out->distance = s.distance + std::abs(s.v) * tau;
  out->wheel_count = wheel_count_;
  const double a = step_start_s(s.k);
  const double b = static_cast<double>(s.k * kStepNs + tau_ns) * 1e-9;
  for (int w = 0; w < wheel_count_; ++w) {
    const double ground = s.side[wheel_left_[w] ? 0 : 1];
    const double noise_end = slip_.noise_fraction(w, b);
    double slipped = ground * (0.5 * (s.noise_start[w] + noise_end)) * tau;
    for (int i = 0; i < slip_.episode_count(); ++i) {
      const WheelSlipModel::Episode& e = slip_.episode(i);
      if ((e.wheel_mask & (1u << w)) == 0) continue;
      const double overlap = std::min(b, e.end) - std::max(a, e.start);
      if (overlap > 0.0) slipped += e.fraction * ground * overlap;
    }
    out->wheel_distance[w] = s.wheel_distance[w] + ground * tau + slipped;
    out->wheel_slip[w] = noise_end + slip_.episode_fraction(w, b);
  }
}

TruthState CommandedTruth::truth_at(double t_s) noexcept {
  TruthState out;
  out.wheel_count = wheel_count_;
  if (!(t_s >= 0.0)) {  // before the start (or NaN): at rest at the origin
    out.t = t_s;
    for (int w = 0; w < wheel_count_; ++w) {
      out.wheel_slip[w] = slip_.noise_fraction(w, 0.0) + slip_.episode_fraction(w, 0.0);
    }
    return out;
  }
  // Nanoseconds as the devices count them (their t - t0), so that readers
  // asking for the same instant land on the same step and offset.
  const TimeNs t_ns = t_s < static_cast<double>(kCommandTimeLimitNs) * 1e-9 ? static_cast<TimeNs>(std::llround(t_s * 1e9))
                                                                           : kCommandTimeLimitNs;
  std::int64_t k = t_ns / kStepNs;
  TimeNs tau = t_ns - k * kStepNs;
  double answered = t_s;
  if (k > last_) {
    const std::int64_t reach = std::max<std::int64_t>(last_, 0) + kMaxStepsPerQuery;
    if (k > reach) {
      bump_counter(far_queries_);
      k = reach;
      tau = 0;
      answered = step_start_s(k);
    }
    advance_to(k);
  } else {
    const std::int64_t oldest = std::max<std::int64_t>(last_ - (kHistorySteps - 1), 0);
    if (k < oldest) {
      bump_counter(history_misses_);
      k = oldest;
      tau = 0;
      answered = step_start_s(k);
    }
  }
  evolve(steps_[k % kHistorySteps], tau, &out);
  out.t = answered;
  return out;
}

}  // namespace rtfuse::sim
