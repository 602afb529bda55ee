#pragma once
// The navigator as a registered device: a worker on the mapper's grids, the
// loop's estimates and the goals that arrive over LCM (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& navigator_descriptor() noexcept;

}  // namespace rtfuse
