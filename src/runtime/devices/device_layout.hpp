#pragma once
// The diagnostics slots of a configuration, in a fixed order: each enabled
// registered device's slots in registry order, then the navsat transforms'
// (fusion/navsat_status.hpp). The publisher sizes its diagnostics message
// from this once, and the loop fills the same slots every tick.
#include "runtime/config/config.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/fusion/device_status.hpp"

namespace rtfuse {

// The first slot of each registered device (-1: not enabled) and the count
// of device slots (the navsat transforms' first slot).
struct DeviceLayout {
  DeviceLayout() noexcept {
    for (int& s : first_slot) s = -1;
  }
  int first_slot[kMaxDeviceTypes];
  int device_slots = 0;
};

DeviceLayout device_layout(const RuntimeConfig& cfg) noexcept;

// Names, hardware ids and the counter keys (values 0, level stale) of every
// slot; returns the slots used (0 when they would not fit in max).
int describe_devices(const RuntimeConfig& cfg, DeviceStatus* out, int max) noexcept;

}  // namespace rtfuse
