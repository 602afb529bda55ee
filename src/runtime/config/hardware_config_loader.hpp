#pragma once
// [hardware], [can], [[can.node]], [wheel_odometry], [mpu] -> HardwareConfig,
// and the [[sensor]] entries those drivers feed. Configuration time only.
#include <string>
#include <vector>

#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {

// Where each stored sensor was written ("sensor[1]", "instance[0].sensor[2]"),
// in cfg.sensors' order: errors about a sensor found later point there.
struct SensorSite {
  std::string key;
  toml::source_region where;
};

// Call after the [[sensor]] entries are read (it checks their source keys).
void read_hardware(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sensors);

}  // namespace rtfuse::config
