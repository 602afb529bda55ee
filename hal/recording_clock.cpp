#include "hal/recording_clock.hpp"

namespace rtfuse::hal {

TimeNs RecordingClock::now() const noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kClockNow;
  ev.time_ns = inner_.now();
  ev.clock_ns = ev.time_ns;
  tap_.push(ev);
  return ev.clock_ns;
}

void RecordingClock::sleep_until(TimeNs t) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kClockSleepUntil;
  ev.time_ns = inner_.now();
  ev.clock_ns = t;
  // Pushed before sleeping, so the recorder sees it while the thread sleeps.
  tap_.push(ev);
  inner_.sleep_until(t);
}

}  // namespace rtfuse::hal
