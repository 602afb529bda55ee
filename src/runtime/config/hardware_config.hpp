#pragma once
// The devices the process drives itself: where their buses come from, each
// registered device's own section (declared in its folder under devices/,
// plain values), and which [[sensor]] each device source feeds.
// Schema: docs/configuration.md.
#include <array>
#include <cstdint>
#include <string>

#include "runtime/devices/camera/camera_section.hpp"
#include "runtime/devices/gnss/gnss_section.hpp"
#include "runtime/devices/imu/mpu_section.hpp"
#include "runtime/devices/mapper/mapping_section.hpp"
#include "runtime/devices/navigator/navigation_section.hpp"
#include "runtime/devices/visual_odometry/vo_section.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoders_section.hpp"

namespace rtfuse {

// Where the bus primitives come from: the kernel (SocketCAN, i2c-dev,
// libgpiod, V4L2, termios), the bus-level simulated robot, or nothing (LCM
// inputs only).
enum class HalBackend : std::uint8_t { kNone, kLinux, kSim };

// [[sensor]] sources the registered devices offer (devices/device_registry).
constexpr int kMaxDeviceSources = 8;

constexpr std::array<int, kMaxDeviceSources> no_source_sensors() noexcept {
  std::array<int, kMaxDeviceSources> a{};
  for (int& s : a) s = -1;
  return a;
}

struct HardwareConfig {
  HalBackend backend = HalBackend::kNone;
  std::string scenario;  // backend "sim": the drive scenario file (resolved path)
  // One member per registered device's section.
  CanSection can;
  WheelOdometrySection wheel_odometry;
  MpuSection mpu;
  CameraSection camera;
  VoSection vo;
  GnssSection gnss;
  MappingSection mapping;
  NavigationSection navigation;
  // Per device source (device_source(id)): the [[sensor]] it feeds, -1 none.
  std::array<int, kMaxDeviceSources> source_sensor = no_source_sensors();
};

}  // namespace rtfuse
