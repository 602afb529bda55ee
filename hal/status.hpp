#pragma once
// Outcome of one bus operation. Distinct values per failure so drivers can
// count and react (a NACK is a missing or busy device, a bus error is wiring).
#include <cstdint>

namespace rtfuse::hal {

enum class HalStatus : std::uint8_t {
  kOk,
  kTimeout,     // nothing arrived / the transfer did not complete in time
  kWouldBlock,  // non-blocking call, nothing ready (not an error)
  kNack,        // I2C: the device did not acknowledge (ENXIO / EREMOTEIO)
  kBusError,    // arbitration lost, bus-off, electrical fault (EIO, EAGAIN on I2C)
  kIoError,     // any other errno; the backend keeps the errno text for diagnostics
  kClosed,      // the device went away (ENODEV, interface down)
  kMalformed,   // bytes from the kernel that do not form a valid record
};

const char* to_string(HalStatus s) noexcept;

}  // namespace rtfuse::hal
