#pragma once
// The devices' part of the configuration: [hardware] (where the buses come
// from), each registered device's own sections (read by its descriptor),
// and the [[sensor]] entries the devices feed, checked against what each
// source produces. Configuration time only.
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

// The top-level sections the registered devices read.
std::vector<std::string_view> device_sections();

// Call after the [[sensor]] entries are read (it checks their source keys).
void read_devices(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sensors);

// A path relative to the config file, so a config and its files move together.
std::string relative_to_config(const std::string& path, const std::string& config_file);

}  // namespace rtfuse::config
