#pragma once
// Health of the devices the process drives itself (encoder nodes, the CAN
// bus, the IMU, ...) and of the navsat transforms, in the snapshot the loop
// publishes. Trivially copyable: the
// counter names are pointers to string literals, fixed per configuration,
// and the last error's text is stored inline.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>

#include "core/fixed_string.hpp"

namespace rtfuse {

constexpr int kMaxDevices = 16;
constexpr int kMaxDeviceValues = 20;

enum class DeviceLevel : std::int8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };

// The device's last error in words, as diagnostic_msgs/DiagnosticStatus's
// message: "" while there has been none.
using DeviceMessage = FixedString<127>;

// Stores text (null: ""), cut to fit with "..." at the end when longer.
inline void set_device_message(DeviceMessage& m, const char* text) noexcept {
  constexpr std::size_t kMax = DeviceMessage::max_size();
  const std::size_t n = text == nullptr ? 0 : std::strlen(text);
  if (n <= kMax) {
    m.assign(std::string_view(text == nullptr ? "" : text, n));
    return;
  }
  char cut[kMax + 1];
  std::memcpy(cut, text, kMax - 3);
  std::memcpy(cut + kMax - 3, "...", 3);
  m.assign(std::string_view(cut, kMax));
}

struct DeviceStatus {
  FixedString<47> name;
  FixedString<47> hardware_id;
  FixedString<23> state;
  DeviceMessage message;
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

// A slot's counters are named once, in an array of string literals next to
// the code that fills them: the layout names the slot with the keys (values
// 0) and the device sets the values in the same order every tick.
template <std::size_t N>
void describe_keys(DeviceStatus& d, const char* const (&keys)[N]) noexcept {
  static_assert(N <= static_cast<std::size_t>(kMaxDeviceValues), "more counters than a device slot holds");
  d.num_values = 0;
  for (const char* k : keys) d.add(k, 0);
}

template <std::size_t N>
void set_device_values(DeviceStatus& d, const char* const (&keys)[N],
                       std::initializer_list<std::int64_t> values) noexcept {
  d.num_values = 0;
  std::size_t i = 0;
  for (std::int64_t v : values) {
    if (i == N) break;
    d.add(keys[i++], v);
  }
}

}  // namespace rtfuse
