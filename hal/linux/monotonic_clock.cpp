#include "hal/linux/monotonic_clock.hpp"

#include <cerrno>
#include <ctime>

namespace rtfuse::hal {

TimeNs MonotonicClock::now() const noexcept { return monotonic_now_ns(); }

void MonotonicClock::sleep_until(TimeNs t) noexcept {
  // A negative time would give a negative tv_nsec, which the kernel rejects
  // with EINVAL instead of returning at once.
  const timespec deadline = ns_to_timespec(t > 0 ? t : 0);
  // clock_nanosleep returns the error number instead of setting errno. The
  // deadline is absolute, so resuming after EINTR needs no remaining-time
  // bookkeeping.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

}  // namespace rtfuse::hal
