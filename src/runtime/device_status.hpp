#pragma once
// Health of the devices the process drives itself (encoder nodes, the CAN
// bus, the IMU), in the snapshot the loop publishes. Trivially copyable: the
// counter names are pointers to string literals, fixed per configuration.
#include <cstdint>

#include "core/fixed_string.hpp"

namespace rtfuse {

constexpr int kMaxDevices = 12;
constexpr int kMaxDeviceValues = 20;

enum class DeviceLevel : std::int8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };

struct DeviceStatus {
  FixedString<47> name;
  FixedString<47> hardware_id;
  FixedString<23> state;
  DeviceLevel level = DeviceLevel::kStale;
  int num_values = 0;
  const char* keys[kMaxDeviceValues] = {};
  std::int64_t values[kMaxDeviceValues] = {};

  // Appends one counter; the key must be a string literal.
  void add(const char* key, std::int64_t value) noexcept {
    if (num_values < kMaxDeviceValues) {
      keys[num_values] = key;
      values[num_values] = value;
      ++num_values;
    }
  }
};

}  // namespace rtfuse
