#pragma once
// The CANopen wheel encoders as a registered device (device_descriptor.hpp).
#include "runtime/devices/device_descriptor.hpp"

namespace rtfuse {

const DeviceDescriptor& wheel_encoders_descriptor() noexcept;

// The COB-IDs the encoder driver listens to (TPDO, heartbeat, EMCY of every
// node): the kernel drops everything else before it reaches the loop.
int encoder_can_ids(const CanSection& can, std::uint32_t* ids, int max);

}  // namespace rtfuse
