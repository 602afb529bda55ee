#include "runtime/devices/mapper/mapper_descriptor.hpp"

#include <cstdio>

#include "runtime/devices/mapper/mapper_device.hpp"
#include "runtime/devices/mapper/mapping_config.hpp"

namespace rtfuse {
namespace {

class MapperDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "mapper"; }
  // Keyframes take tens of milliseconds: never on the camera's thread.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kWorker; }
  const char* host() const noexcept override { return "camera"; }
  std::vector<std::string_view> sections() const override { return {"mapping"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_mapping_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override {
    return cfg.hardware.camera.enabled && cfg.hardware.mapping.enabled;
  }
  std::string bus_path(const RuntimeConfig& cfg) const override {
    return std::string(cfg.hardware.camera.device.view());
  }
  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    char buf[160];
    DeviceStatus& d = out[0];
    d.name = "mapper";
    std::snprintf(buf, sizeof buf, "%s %g m", cfg.hardware.camera.device.c_str(), cfg.hardware.mapping.resolution_m);
    d.hardware_id = buf;
    describe_keys(d, kMapperKeys);
  }
  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses&, std::string* error) const override {
    if (ctx.host == nullptr || ctx.host->frame_source() == nullptr) {
      *error = "[mapping] needs the camera's frames, and no camera was made";
      return nullptr;
    }
    return MapperDevice::create(*ctx.host->frame_source(), ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& mapper_descriptor() noexcept {
  static const MapperDescriptor d;
  return d;
}

}  // namespace rtfuse
