#pragma once
// A GNSS receiver on a serial port as a registered device (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& gnss_descriptor() noexcept;

}  // namespace rtfuse
