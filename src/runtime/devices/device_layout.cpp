#include "runtime/devices/device_layout.hpp"

#include "runtime/devices/device_registry.hpp"
#include "runtime/fusion/navsat_status.hpp"
#include "runtime/fusion/standstill_status.hpp"

namespace rtfuse {

DeviceLayout device_layout(const RuntimeConfig& cfg) noexcept {
  DeviceLayout l;
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(cfg)) continue;
    l.first_slot[i] = l.device_slots;
    l.device_slots += d.slot_count(cfg);
  }
  return l;
}

int describe_devices(const RuntimeConfig& cfg, DeviceStatus* out, int max) noexcept {
  const DeviceLayout l = device_layout(cfg);
  const int navsat = navsat_slot_count(cfg);
  const int standstill = standstill_slot_count(cfg);
  const int count = l.device_slots + navsat + standstill;
  if (count > max) return 0;
  for (int i = 0; i < count; ++i) out[i] = DeviceStatus{};
  for (int i = 0; i < device_type_count(); ++i) {
    if (l.first_slot[i] >= 0) device_type(i).describe(cfg, out + l.first_slot[i]);
  }
  describe_navsat(cfg, out + l.device_slots);
  describe_standstill(cfg, out + l.device_slots + navsat);
  return count;
}

}  // namespace rtfuse
