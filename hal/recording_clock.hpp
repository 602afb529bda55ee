#pragma once
// A Clock that forwards to the real one and records every now() result and
// every sleep_until() deadline, so a thread that paces itself by polling the
// clock (the IMU thread without a data-ready line) replays with the same
// times. Never allocates; a full ring loses the event and counts it.
//
// One instance per thread: the loop's clock and the IMU thread's are separate
// decorators on separate rings. Give the other decorators the inner clock,
// not this one, or their time stamps would be recorded as clock reads.
#include <cstdint>

#include "hal/bus_event.hpp"
#include "hal/clock.hpp"

namespace rtfuse::hal {

class RecordingClock final : public Clock {
 public:
  RecordingClock(Clock& inner, SpscRing<BusEvent>& ring, std::uint8_t device) noexcept
      : inner_(inner), tap_(ring, device) {}

  // Const in the interface; recording is not part of the clock's state.
  TimeNs now() const noexcept override;
  // Records the deadline with the time of the call, then sleeps.
  void sleep_until(TimeNs t) noexcept override;

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  Clock& inner_;
  mutable BusEventTap tap_;
};

}  // namespace rtfuse::hal
