#pragma once
// A CanBus that forwards every call to the real one and records the call and
// its result (frames, status, bus state) as a BusEvent, for rtfused --record.
// Never blocks or allocates; a full ring loses the event and counts it.
//
// receive() passes at most kBusEventMaxFrames as `max` to the inner bus, so
// one call is one event; replay applies the same cap, so a driver sees the
// same frames per call in both.
//
// `clock` stamps time_ns; it must not itself be a recording clock (that would
// record its reads too). One instance per thread: the ring is that thread's.
#include <cstdint>

#include "hal/bus_event.hpp"
#include "hal/can_bus.hpp"
#include "hal/clock.hpp"

namespace rtfuse::hal {

class RecordingCanBus final : public CanBus {
 public:
  RecordingCanBus(CanBus& inner, SpscRing<BusEvent>& ring, std::uint8_t device,
                  const Clock* clock = nullptr) noexcept
      : inner_(inner), tap_(ring, device), clock_(clock) {}

  HalStatus send(const CanFrame& frame) noexcept override;
  int receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept override;
  CanBusState state() const noexcept override { return inner_.state(); }
  const char* last_error() const noexcept override { return inner_.last_error(); }

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  CanBus& inner_;
  BusEventTap tap_;
  const Clock* clock_;
};

}  // namespace rtfuse::hal
