#pragma once
// The ZED-class stereo camera as a registered device (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& camera_descriptor() noexcept;

}  // namespace rtfuse
