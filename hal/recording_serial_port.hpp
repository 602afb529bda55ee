#pragma once
// A SerialPort that forwards to the real one and records every read (the
// bytes, their stamp, the status) and write as BusEvents. A read asks the
// port for at most kBusEventMaxBytes, so one call is one event (the
// SerialPort contract already lets read return fewer than asked); a longer
// write goes out, and is recorded, in pieces of that size. Never blocks
// beyond the port's own wait, never allocates; a full ring loses the event
// and counts it. One instance per thread (the ring is that thread's).
#include <cstdint>

#include "hal/bus_event.hpp"
#include "hal/clock.hpp"
#include "hal/serial_port.hpp"

namespace rtfuse::hal {

class RecordingSerialPort final : public SerialPort {
 public:
  RecordingSerialPort(SerialPort& inner, SpscRing<BusEvent>& ring, std::uint8_t device,
                      const Clock* clock = nullptr) noexcept
      : inner_(inner), tap_(ring, device), clock_(clock) {}

  int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept override;
  HalStatus write(const std::uint8_t* data, int size) noexcept override;
  const char* last_error() const noexcept override { return inner_.last_error(); }
  bool reopen() noexcept override;

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  SerialPort& inner_;
  BusEventTap tap_;
  const Clock* clock_;
};

}  // namespace rtfuse::hal
