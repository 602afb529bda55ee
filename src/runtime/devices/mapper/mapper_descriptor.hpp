#pragma once
// The occupancy mapper as a registered device: a worker on the camera's
// pairs and the loop's estimates (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& mapper_descriptor() noexcept;

}  // namespace rtfuse
