#include "runtime/devices/device_registry.hpp"

#include "runtime/devices/camera/camera_descriptor.hpp"
#include "runtime/devices/gnss/gnss_descriptor.hpp"
#include "runtime/devices/imu/imu_descriptor.hpp"
#include "runtime/devices/mapper/mapper_descriptor.hpp"
#include "runtime/devices/navigator/navigator_descriptor.hpp"
#include "runtime/devices/visual_odometry/visual_odometry_descriptor.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoders_descriptor.hpp"

namespace rtfuse {
namespace {

// The order is the diagnostics' and the recording's: keep it when adding one.
const DeviceDescriptor* const kDevices[] = {
    &wheel_encoders_descriptor(),
    &imu_descriptor(),
    &camera_descriptor(),
    &visual_odometry_descriptor(),
    &gnss_descriptor(),
    &mapper_descriptor(),
    &navigator_descriptor(),
};
constexpr int kDeviceCount = static_cast<int>(sizeof(kDevices) / sizeof(kDevices[0]));
static_assert(kDeviceCount <= kMaxDeviceTypes, "raise kMaxDeviceTypes");

struct SourceTable {
  DeviceSource sources[kMaxDeviceSources];
  int count = 0;
  SourceTable() {
    for (const DeviceDescriptor* d : kDevices) {
      for (const DeviceSource& s : d->sources()) {
        if (count < kMaxDeviceSources) sources[count++] = s;
      }
    }
  }
};

const SourceTable& source_table() {
  static const SourceTable table;
  return table;
}

}  // namespace

int device_type_count() noexcept { return kDeviceCount; }
const DeviceDescriptor& device_type(int i) noexcept { return *kDevices[i]; }

int find_device_type(std::string_view name) noexcept {
  for (int i = 0; i < kDeviceCount; ++i) {
    if (name == kDevices[i]->name()) return i;
  }
  return -1;
}

int device_source_count() noexcept { return source_table().count; }
const DeviceSource& device_source(int id) noexcept { return source_table().sources[id]; }

int find_device_source(std::string_view name) noexcept {
  for (int i = 0; i < device_source_count(); ++i) {
    if (name == device_source(i).name) return i;
  }
  return -1;
}

std::string device_source_names() {
  std::string out = "lcm";
  for (int i = 0; i < device_source_count(); ++i) out += std::string(", ") + device_source(i).name;
  return out;
}

int source_sensor(const RuntimeConfig& cfg, std::string_view name) noexcept {
  const int id = find_device_source(name);
  return id < 0 ? -1 : cfg.hardware.source_sensor[static_cast<std::size_t>(id)];
}

}  // namespace rtfuse
