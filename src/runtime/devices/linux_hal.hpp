#pragma once
// The kernel's buses for a configuration: each enabled registered device
// opens its own (a SocketCAN socket filtered to the encoder nodes' COB-IDs,
// /dev/i2c-N and a data-ready line through libgpiod, a V4L2 stream, a tty)
// on CLOCK_MONOTONIC. Opened once before start(); a missing kernel feature
// or device fails here with the device, errno text and likely fix.
#include <memory>
#include <string>

#include "hal/linux/monotonic_clock.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"

namespace rtfuse {

class LinuxHal {
 public:
  static std::unique_ptr<LinuxHal> open(const RuntimeConfig& cfg, std::string* error);
  HalBuses buses() const { return buses_; }
  // One line per opened bus and how it is driven ("IMU bus /dev/i2c-1: SMBus
  // (I2C block reads, byte writes)"), for the start-up log: an SMBus-only
  // adapter works but reads long bursts in pieces, which the user should know.
  const std::string& describe() const { return description_; }

 private:
  LinuxHal() = default;
  BusKeeper keep_;
  hal::MonotonicClock clock_;
  HalBuses buses_;
  std::string description_;
};

}  // namespace rtfuse
