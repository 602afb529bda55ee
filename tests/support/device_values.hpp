#pragma once
// A device's slot and counters in a snapshot, by the names diagnostics
// give them, and a config's errors as one text: what the drive tests look
// at after a run.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/snapshot.hpp"

namespace rtfuse::test {

inline std::string config_errors(const ConfigLoadResult& r) {
  std::string all;
  for (const ConfigError& e : r.errors) all += e.to_string() + "\n";
  return all;
}

// The slot named `name`, or null.
inline const DeviceStatus* find_device(const Snapshot& s, const char* name) {
  for (int i = 0; i < s.num_devices; ++i) {
    if (std::string(s.devices[i].name.c_str()) == name) return &s.devices[i];
  }
  return nullptr;
}

// The counter `key` of a slot; a test failure and -1 when it has none.
inline std::int64_t device_value(const DeviceStatus& d, const char* key) {
  for (int i = 0; i < d.num_values; ++i) {
    if (std::string(d.keys[i]) == key) return d.values[i];
  }
  ADD_FAILURE() << "no key " << key << " in device " << d.name.c_str();
  return -1;
}

}  // namespace rtfuse::test
