#include "runtime/devices/visual_odometry/visual_odometry_descriptor.hpp"


#include "runtime/devices/camera_consumer_descriptor.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/visual_odometry/visual_odometry_device.hpp"
#include "runtime/devices/visual_odometry/vo_config.hpp"

namespace rtfuse {
namespace {

class VisualOdometryDescriptor final : public CameraConsumerDescriptor {
 public:
  const char* name() const noexcept override { return "visual_odometry"; }
  // Every pair, on the camera's thread: its twists then come before the
  // ticks they were measured for, in a replay as live.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kHostThread; }
  std::vector<std::string_view> sections() const override { return {"vo"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_vo_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override {
    return cfg.hardware.camera.enabled && cfg.hardware.vo.enabled && source_sensor(cfg, "stereo_vo") >= 0;
  }
  std::vector<DeviceSource> sources() const override {
    return {{"stereo_vo", est::SensorKind::kTwist, "twist", "vo"}};
  }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    describe_slot(cfg, out[0], "visual odometry", cfg.hardware.camera.frame.c_str(), kVoKeys);
  }
  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses&, std::string* error) const override {
    FrameSource* camera = camera_of(ctx, "vo", error);
    return camera == nullptr ? nullptr : VisualOdometryDevice::create(*camera, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& visual_odometry_descriptor() noexcept {
  static const VisualOdometryDescriptor d;
  return d;
}

}  // namespace rtfuse
