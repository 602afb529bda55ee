#pragma once
// [hardware], [can], [[can.node]], [wheel_odometry], [mpu] -> HardwareConfig,
// and the [[sensor]] entries those drivers feed. Configuration time only.
#include "runtime/toml_reader.hpp"

namespace rtfuse::config {

// Call after the [[sensor]] entries are read (it checks their source keys).
void read_hardware(const Section& root, RuntimeConfig& cfg);

}  // namespace rtfuse::config
