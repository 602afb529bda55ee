#pragma once
// An I2cBus that answers from a recording: each transfer is checked against
// the next recorded call of its ReplayStream (address, register, length or
// written value) and returns the recorded status and bytes; retries() follows
// the recorded counter. After a divergence every transfer returns kClosed.
// Never blocks or allocates.
#include <cstdint>

#include "hal/i2c_bus.hpp"
#include "hal/replay/replay_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayI2cBus final : public I2cBus {
 public:
  ReplayI2cBus(ReplayStream& stream, std::uint8_t device) noexcept : stream_(stream), device_(device) {}

  HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept override;
  const char* last_error() const noexcept override;
  std::int64_t retries() const noexcept override { return retries_; }

  std::uint8_t device() const noexcept { return device_; }

 private:
  const BusEvent* take(const BusEvent& call) noexcept;

  ReplayStream& stream_;
  std::uint8_t device_;
  std::int64_t retries_ = 0;
  HalStatus last_status_ = HalStatus::kOk;
};

}  // namespace rtfuse::hal::replay
