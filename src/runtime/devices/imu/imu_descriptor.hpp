#pragma once
// The MPU IMU as a registered device (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& imu_descriptor() noexcept;

}  // namespace rtfuse
