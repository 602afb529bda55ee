#pragma once
// The live process clock: CLOCK_MONOTONIC, and an absolute-time sleep.
// Sleeping to an absolute deadline (TIMER_ABSTIME) keeps a fixed-rate loop
// free of drift: a relative sleep would add each tick's work time and each
// wake-up latency to the period.
#include "hal/clock.hpp"

namespace rtfuse::hal {

class MonotonicClock final : public Clock {
 public:
  TimeNs now() const noexcept override;
  // Returns at or after t (CLOCK_MONOTONIC ns); a deadline already passed
  // returns at once. Signals do not cut the sleep short.
  void sleep_until(TimeNs t) noexcept override;
};

}  // namespace rtfuse::hal
