#pragma once
// An I2cBus that forwards every transfer to the real one and records the
// transfer and its result (bytes read, status after retries, the retry
// counter) as a BusEvent. Never blocks or allocates; a full ring loses the
// event and counts it. One instance per thread (the ring is that thread's).
#include <cstdint>

#include "hal/bus_event.hpp"
#include "hal/clock.hpp"
#include "hal/i2c_bus.hpp"

namespace rtfuse::hal {

class RecordingI2cBus final : public I2cBus {
 public:
  RecordingI2cBus(I2cBus& inner, SpscRing<BusEvent>& ring, std::uint8_t device,
                  const Clock* clock = nullptr) noexcept
      : inner_(inner), tap_(ring, device), clock_(clock) {}

  HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept override;
  const char* last_error() const noexcept override { return inner_.last_error(); }
  std::int64_t retries() const noexcept override { return inner_.retries(); }

  std::int64_t overflows() const noexcept { return tap_.overflows(); }
  std::uint8_t device() const noexcept { return tap_.device(); }

 private:
  I2cBus& inner_;
  BusEventTap tap_;
  const Clock* clock_;
};

}  // namespace rtfuse::hal
