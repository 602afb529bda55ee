#include "runtime/devices/linux_hal.hpp"

namespace rtfuse {

std::unique_ptr<LinuxHal> LinuxHal::open(const RuntimeConfig& cfg, std::string* error) {
  std::unique_ptr<LinuxHal> h(new LinuxHal());
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(cfg)) continue;
    if (!d.open_linux(cfg, h->keep_, h->clock_, &h->buses_.device[i], &h->description_, error)) return nullptr;
  }
  return h;
}

}  // namespace rtfuse
