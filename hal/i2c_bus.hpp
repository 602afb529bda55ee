#pragma once
// An I2C bus: register reads (one combined write-address/read-N transfer) and
// register writes, with a bounded retry policy. No device knowledge.
#include <cstdint>

#include "hal/status.hpp"

namespace rtfuse::hal {

struct I2cRetryPolicy {
  int attempts = 3;  // total tries for NACK / bus error; timeouts are not retried
};

class I2cBus {
 public:
  virtual ~I2cBus() = default;
  // Write `reg`, repeated start, read n bytes (n <= 64). Nothing is written to
  // buf unless kOk.
  virtual HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept = 0;
  virtual HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept = 0;
  virtual const char* last_error() const noexcept = 0;
  // Failed attempts that a retry then recovered, since start (for diagnostics).
  virtual std::int64_t retries() const noexcept = 0;
};

}  // namespace rtfuse::hal
