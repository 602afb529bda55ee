#pragma once
// GPIO decorators for rtfused --record: an edge source (the IMU's data-ready
// line) and an output, each forwarding to the real line and recording the
// call and its result as a BusEvent. Never block beyond what the inner call
// does, never allocate; a full ring loses the event and counts it.
//
// The output decorator is RecordingOutputLine: hal::mock::RecordingGpioOutput
// is already the name of the mock output that logs levels.
#include <cstdint>

#include "hal/bus_event.hpp"
#include "hal/clock.hpp"
#include "hal/gpio.hpp"

namespace rtfuse::hal {

class RecordingEdgeSource final : public GpioEdgeSource {
 public:
  RecordingEdgeSource(GpioEdgeSource& inner, SpscRing<BusEvent>& ring, std::uint8_t device,
                      const Clock* clock = nullptr) noexcept
      : inner_(inner), tap_(ring, device), clock_(clock) {}

  HalStatus wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept override;
  const char* last_error() const noexcept override { return inner_.last_error(); }

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  GpioEdgeSource& inner_;
  BusEventTap tap_;
  const Clock* clock_;
};

class RecordingOutputLine final : public GpioOutput {
 public:
  RecordingOutputLine(GpioOutput& inner, SpscRing<BusEvent>& ring, std::uint8_t device,
                      const Clock* clock = nullptr) noexcept
      : inner_(inner), tap_(ring, device), clock_(clock) {}

  HalStatus set(bool high) noexcept override;
  const char* last_error() const noexcept override { return inner_.last_error(); }

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  GpioOutput& inner_;
  BusEventTap tap_;
  const Clock* clock_;
};

}  // namespace rtfuse::hal
