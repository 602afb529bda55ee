#pragma once
// The bus primitives the drivers of one configuration run on, whatever
// provides them: the kernel (linux_hal), the simulated robot (src/sim), or a
// recording (replay/). One DeviceBuses per registered device, at its index in
// the registry; empty where the configuration has no such device. Not owned.
#include <cassert>
#include <string_view>

#include "runtime/devices/device_buses.hpp"
#include "runtime/devices/device_registry.hpp"

namespace rtfuse {

struct HalBuses {
  DeviceBuses device[kMaxDeviceTypes];

  // The device of that registered name (tests and tools set buses by hand;
  // an unknown name is a programming error).
  DeviceBuses& of(std::string_view name) noexcept { return device[index(name)]; }
  const DeviceBuses& of(std::string_view name) const noexcept { return device[index(name)]; }

 private:
  static int index(std::string_view name) noexcept {
    const int i = find_device_type(name);
    assert(i >= 0 && "no registered device of that name");
    return i < 0 ? 0 : i;
  }
};

}  // namespace rtfuse
