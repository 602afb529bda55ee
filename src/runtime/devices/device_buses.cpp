#include "runtime/devices/device_buses.hpp"

#include <algorithm>
#include <string>
#include <string_view>

#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const char* to_string(BusKind k) noexcept {
  switch (k) {
    case BusKind::kCan: return "CAN bus";
    case BusKind::kI2c: return "I2C bus";
    case BusKind::kEdge: return "data-ready line";
    case BusKind::kVideo: return "video stream";
    case BusKind::kSerial: return "serial port";
    case BusKind::kClock: return "clock";
  }
  return "bus";
}

std::string device_path_name(std::string_view path, const char* fallback) {
  const std::size_t slash = path.rfind('/');
  std::string name(slash == std::string_view::npos ? path : path.substr(slash + 1));
  std::replace(name.begin(), name.end(), ' ', '_');
  return name.empty() ? std::string(fallback) : name;
}

}  // namespace rtfuse
