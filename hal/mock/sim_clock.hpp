#pragma once
// Simulated clock for replay and simulation: time moves only when the loop
// sleeps (or the replayer sets it), so a run is as fast as the CPU allows and
// the same log gives the same output on any machine.
#include <atomic>

#include "hal/clock.hpp"

namespace rtfuse::hal::mock {

class SimClock final : public Clock {
 public:
  explicit SimClock(TimeNs start = 0) noexcept : now_(start) {}

  TimeNs now() const noexcept override { return now_.load(std::memory_order_acquire); }
  // Jumps to t; a deadline in the past leaves the time alone, so simulated
  // time never runs backwards.
  void sleep_until(TimeNs t) noexcept override {
    TimeNs cur = now_.load(std::memory_order_relaxed);
    while (t > cur && !now_.compare_exchange_weak(cur, t, std::memory_order_acq_rel)) {
    }
  }

  // For the replayer, which takes time from the log; may go backwards only if
  // the caller asks for it.
  void set(TimeNs t) noexcept { now_.store(t, std::memory_order_release); }
  void advance(TimeNs dt) noexcept { now_.fetch_add(dt, std::memory_order_acq_rel); }

 private:
  // Atomic because sensor threads read the time while the loop moves it.
  std::atomic<TimeNs> now_;
  static_assert(std::atomic<TimeNs>::is_always_lock_free, "RT path needs lock-free atomics");
};

}  // namespace rtfuse::hal::mock
