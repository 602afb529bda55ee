#pragma once
// The registered kinds of device, in the order their diagnostics slots,
// recording streams and sources are laid out. Adding a device is its folder
// under devices/ and one line in device_registry.cpp (docs/design.md,
// "Adding a device").
#include <string>
#include <string_view>

#include "runtime/config/config.hpp"
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

// Kinds of device a process can drive at once (HalBuses has a slot each).
constexpr int kMaxDeviceTypes = 8;

int device_type_count() noexcept;
const DeviceDescriptor& device_type(int i) noexcept;
// -1 when no registered device has that name.
int find_device_type(std::string_view name) noexcept;

// Every registered device's [[sensor]] sources, flat, in registry order:
// SensorConfig::source and HardwareConfig::source_sensor index this list.
int device_source_count() noexcept;
const DeviceSource& device_source(int id) noexcept;
int find_device_source(std::string_view name) noexcept;
// "lcm, wheel_odometry, mpu, ..." for messages.
std::string device_source_names();
// The sensor that source `name` feeds in cfg, -1 when none.
int source_sensor(const RuntimeConfig& cfg, std::string_view name) noexcept;

}  // namespace rtfuse
