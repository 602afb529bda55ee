#include "runtime/devices/mapper/mapper_descriptor.hpp"

#include <cstdio>

#include "runtime/devices/camera_consumer_descriptor.hpp"
#include "runtime/devices/mapper/mapper_device.hpp"
#include "runtime/devices/mapper/mapping_config.hpp"

namespace rtfuse {
namespace {

class MapperDescriptor final : public CameraConsumerDescriptor {
 public:
  const char* name() const noexcept override { return "mapper"; }
  // Keyframes take tens of milliseconds: never on the camera's thread.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kWorker; }
  std::vector<std::string_view> sections() const override { return {"mapping"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_mapping_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override {
    return cfg.hardware.camera.enabled && cfg.hardware.mapping.enabled;
  }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    char detail[32];
    std::snprintf(detail, sizeof detail, "%g m", cfg.hardware.mapping.resolution_m);
    describe_slot(cfg, out[0], "mapper", detail, kMapperKeys);
  }
  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses&, std::string* error) const override {
    FrameSource* camera = camera_of(ctx, "mapping", error);
    return camera == nullptr ? nullptr : MapperDevice::create(*camera, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& mapper_descriptor() noexcept {
  static const MapperDescriptor d;
  return d;
}

}  // namespace rtfuse
