#pragma once
// The stereo visual odometry as a registered device: a frame consumer of
// the camera (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& visual_odometry_descriptor() noexcept;

}  // namespace rtfuse
