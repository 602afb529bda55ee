#include "runtime/devices/device_config.hpp"

#include <filesystem>
#include <string>
#include <string_view>

#include "runtime/devices/device_registry.hpp"

namespace rtfuse::config {
namespace {

void read_backend(const Section& s, HardwareConfig& hw, const std::string& config_file) {
  s.reject_unknown({"backend", "scenario"});
  std::string backend;
  if (s.read("backend", backend)) {
    if (backend == "none") {
      hw.backend = HalBackend::kNone;
    } else if (backend == "linux") {
      hw.backend = HalBackend::kLinux;
    } else if (backend == "sim") {
      hw.backend = HalBackend::kSim;
    } else {
      s.value_error("backend", "must be one of none, linux, sim, got " + in_quotes(backend));
    }
  }
  std::string scenario;
  if (s.read("scenario", scenario)) {
    if (scenario.empty()) {
      s.value_error("scenario", "must not be empty");
    } else {
      hw.scenario = relative_to_config(scenario, config_file);
    }
  }
  if (hw.backend == HalBackend::kSim && hw.scenario.empty()) {
    s.table_error(s.key("scenario"), "backend \"sim\" needs a scenario file (scenario = \"scenarios/demo.toml\")");
  }
  if (hw.backend != HalBackend::kSim && !hw.scenario.empty()) {
    s.key_error("scenario", "only used with backend = \"sim\"");
  }
}

// The sensor fed by a driver, checked against what the driver produces.
int find_source(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sites, SensorSource source,
                const DeviceSource& what) {
  const std::string_view source_name = what.name, kind_name = what.kind_name, driver_section = what.section;
  const bool driver_configured = section_table(root, driver_section) != nullptr;
  int found = -1;
  for (int i = 0; i < cfg.num_sensors && i < static_cast<int>(sites.size()); ++i) {
    const SensorConfig& sc = cfg.sensors[static_cast<std::size_t>(i)];
    // Another instance's sensor on the same driver shares the first one's ring.
    if (sc.source != source || sensor_input(cfg, i) != i) continue;
    const SensorSite& site = sites[static_cast<std::size_t>(i)];
    const std::string key = site.key + ".source";
    if (found >= 0) {
      root.diag().add(site.where, key, "a second sensor with source = " + in_quotes(source_name) + " (also " +
                                           sites[static_cast<std::size_t>(found)].key + ")");
      continue;
    }
    if (sc.params.kind != what.kind) {
      root.diag().add(site.where, site.key + ".type",
                      "source " + in_quotes(source_name) + " produces type " + in_quotes(kind_name));
    }
    if (!driver_configured) {
      root.diag().add(site.where, key, "source " + in_quotes(source_name) + " needs a [" + std::string(driver_section) +
                                           "] section");
    }
    found = i;
  }
  if (found < 0 && driver_configured) {
    const toml::node* n = root.find(driver_section);
    root.diag().add(n ? n->source() : toml::source_region{}, std::string(driver_section),
                    "no [[sensor]] with source = " + in_quotes(source_name) + " fuses it");
  }
  return found;
}

}  // namespace

std::string relative_to_config(const std::string& path, const std::string& config_file) {
  std::filesystem::path p(path);
  if (p.is_relative() && !config_file.empty() && config_file.front() != '<') {
    p = std::filesystem::path(config_file).parent_path() / p;
  }
  return p.lexically_normal().string();
}

std::vector<std::string_view> device_sections() {
  std::vector<std::string_view> out{"hardware"};
  for (int i = 0; i < device_type_count(); ++i) {
    for (std::string_view s : device_type(i).sections()) out.push_back(s);
  }
  return out;
}

void read_devices(const Section& root, RuntimeConfig& cfg, const std::vector<SensorSite>& sites) {
  HardwareConfig& hw = cfg.hardware;
  Diagnostics& d = root.diag();
  read_backend(Section(section_table(root, "hardware"), "hardware", d), hw, cfg.source);
  const char* first_section = nullptr;
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& dev = device_type(i);
    dev.read_config(root, cfg);
    // A device's first section is the one that turns it on; a frame
    // consumer's needs its host's, which says so itself.
    const std::vector<std::string_view> sections = dev.sections();
    if (first_section == nullptr && dev.host() == nullptr && !sections.empty() &&
        section_table(root, sections.front()) != nullptr) {
      first_section = sections.front().data();
    }
  }
  if (first_section != nullptr && hw.backend == HalBackend::kNone) {
    const Section s(section_table(root, first_section), first_section, d);
    s.table_error("hardware.backend", std::string("[") + first_section +
                                          "] needs hardware.backend = \"linux\" (real devices) or \"sim\"");
  }
  for (int id = 0; id < device_source_count(); ++id) {
    hw.source_sensor[static_cast<std::size_t>(id)] =
        find_source(root, cfg, sites, static_cast<SensorSource>(id), device_source(id));
  }
}

}  // namespace rtfuse::config
