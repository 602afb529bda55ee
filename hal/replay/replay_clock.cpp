#include "hal/replay/replay_clock.hpp"

namespace rtfuse::hal::replay {

TimeNs ReplayClock::now() const noexcept {
  BusEvent call;
  call.kind = BusEventKind::kClockNow;
  call.device = device_;
  const BusEvent* rec = stream_.take(call);
  if (rec != nullptr) last_ = rec->clock_ns;
  return last_;
}

void ReplayClock::sleep_until(TimeNs t) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kClockSleepUntil;
  call.device = device_;
  call.clock_ns = t;
  stream_.take(call);
}

}  // namespace rtfuse::hal::replay
