#pragma once
// Fixed-rate schedule on absolute CLOCK_MONOTONIC deadlines, so the period
// never drifts with the work done; overruns are counted, missed periods skipped.
#include <cstdint>

#include "core/time.hpp"
#include "runtime/fusion/snapshot.hpp"

namespace rtfuse {

class LoopTimer {
 public:
  LoopTimer(double rate_hz, TimeNs start);
  // Deadline of the tick about to run.
  TimeNs deadline() const noexcept { return next_; }
  // Record a tick that woke at `woke` and finished at `done`; advances the
  // deadline, skipping periods that have already passed.
  void record(TimeNs woke, TimeNs done) noexcept;
  const LoopStats& stats() const noexcept { return stats_; }

 private:
  TimeNs period_;
  TimeNs next_;
  std::int64_t jitter_sum_ = 0;
  std::int64_t duration_sum_ = 0;
  LoopStats stats_;
};

}  // namespace rtfuse
