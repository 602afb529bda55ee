#pragma once
// The real buses of a configuration: a SocketCAN socket filtered to the
// encoder nodes' COB-IDs, /dev/i2c-N for the IMU, its data-ready line through
// libgpiod, CLOCK_MONOTONIC. Opened once before start(); a missing kernel
// feature or device fails here with the device, errno text and likely fix.
#include <memory>
#include <string>

#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"

namespace rtfuse {

class LinuxHal {
 public:
  static std::unique_ptr<LinuxHal> open(const RuntimeConfig& cfg, std::string* error);
  ~LinuxHal();
  HalBuses buses() const { return buses_; }
  // One line per opened bus and how it is driven ("IMU bus /dev/i2c-1: SMBus
  // (I2C block reads, byte writes)"), for the start-up log: an SMBus-only
  // adapter works but reads long bursts in pieces, which the user should know.
  std::string describe() const;

 private:
  LinuxHal();
  struct Devices;
  std::unique_ptr<Devices> devices_;
  HalBuses buses_;
};

// The COB-IDs the encoder driver listens to (TPDO, heartbeat, EMCY of every
// node): the kernel drops everything else before it reaches the loop.
int encoder_can_ids(const CanSection& can, std::uint32_t* ids, int max);

}  // namespace rtfuse
