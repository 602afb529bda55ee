#pragma once
// The process clock: CLOCK_MONOTONIC live, a simulated clock in replay and
// simulation (the loop then runs in lockstep with the log).
#include "core/time.hpp"

namespace rtfuse::hal {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual TimeNs now() const noexcept = 0;
  // Absolute-time sleep; the only blocking call the loop makes.
  virtual void sleep_until(TimeNs t) noexcept = 0;
};

}  // namespace rtfuse::hal
