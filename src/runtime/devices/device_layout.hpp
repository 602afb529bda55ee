#pragma once
// Which devices a configuration drives and the counters each one reports, in
// a fixed order: the publisher sizes its diagnostics message from this once,
// and the loop fills the same slots every tick (runtime/hardware.cpp).
#include <initializer_list>

#include "runtime/config/config.hpp"
#include "runtime/fusion/device_status.hpp"

namespace rtfuse {

// Slot order: CAN bus, then one per encoder node in [[can.node]] order, then
// wheel odometry, then the IMU, then the camera, then its visual odometry,
// then the GNSS receiver, then one navsat transform per navsat sensor in
// [[sensor]] order.
struct DeviceSlots {
  int can_bus = -1;
  int first_node = -1;
  int wheel_odometry = -1;
  int imu = -1;
  int camera = -1;
  int vo = -1;
  int gnss = -1;
  int first_navsat = -1;
  int num_navsat = 0;
  int count = 0;
};

DeviceSlots device_slots(const RuntimeConfig& cfg) noexcept;

// Names, hardware ids and the counter keys (values 0, level stale).
int describe_devices(const RuntimeConfig& cfg, DeviceStatus* out, int max) noexcept;

// Counter keys per device kind, in the order the values are filled.
extern const char* const kCanBusKeys[];
extern const int kCanBusKeyCount;
extern const char* const kEncoderNodeKeys[];
extern const int kEncoderNodeKeyCount;
extern const char* const kWheelOdometryKeys[];
extern const int kWheelOdometryKeyCount;
extern const char* const kImuKeys[];
extern const int kImuKeyCount;
extern const char* const kCameraKeys[];
extern const int kCameraKeyCount;
extern const char* const kVoKeys[];
extern const int kVoKeyCount;
extern const char* const kGnssKeys[];
extern const int kGnssKeyCount;
extern const char* const kNavsatKeys[];
extern const int kNavsatKeyCount;

// Values in the order of the layout's keys, so the names are written in
// one place only.
inline void set_device_values(DeviceStatus& d, const char* const* keys, int n,
                              std::initializer_list<std::int64_t> values) noexcept {
  d.num_values = 0;
  int i = 0;
  for (std::int64_t v : values) {
    if (i == n) break;
    d.add(keys[i++], v);
  }
}

}  // namespace rtfuse
