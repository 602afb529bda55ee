#include "runtime/live/loop_timer.hpp"

#include <cerrno>
#include <cmath>
#include <ctime>

namespace rtfuse {

LoopTimer::LoopTimer(double rate_hz, TimeNs start)
    : period_(static_cast<TimeNs>(std::llround(1e9 / rate_hz))), next_(start + period_) {
  stats_.rate_hz = rate_hz;
  stats_.period_ns = period_;
}

void LoopTimer::record(TimeNs woke, TimeNs done) noexcept {
  const std::int64_t jitter = woke > next_ ? woke - next_ : next_ - woke;
  const std::int64_t duration = done - woke;
  ++stats_.ticks;
  jitter_sum_ += jitter;
  duration_sum_ += duration;
  if (jitter > stats_.jitter_max_ns) stats_.jitter_max_ns = jitter;
  if (duration > stats_.tick_duration_max_ns) stats_.tick_duration_max_ns = duration;
  stats_.jitter_mean_ns = jitter_sum_ / stats_.ticks;
  stats_.tick_duration_mean_ns = duration_sum_ / stats_.ticks;
  next_ += period_;
  if (done > next_) {
    // The tick ran into the next period: count it and restart the schedule
    // from now instead of firing a burst of late ticks.
    const std::int64_t missed = (done - next_) / period_ + 1;
    stats_.overruns += missed;
    next_ += missed * period_;
  }
}

}  // namespace rtfuse
