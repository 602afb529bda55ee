#include "runtime/devices/visual_odometry/visual_odometry_descriptor.hpp"

#include <cstdio>

#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/visual_odometry/visual_odometry_device.hpp"
#include "runtime/devices/visual_odometry/vo_config.hpp"

namespace rtfuse {
namespace {

class VisualOdometryDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "visual_odometry"; }
  // Every pair, on the camera's thread: its twists then come before the
  // ticks they were measured for, in a replay as live.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kHostThread; }
  const char* host() const noexcept override { return "camera"; }
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
  std::string bus_path(const RuntimeConfig& cfg) const override {
    return std::string(cfg.hardware.camera.device.view());
  }

  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    char buf[160];
    DeviceStatus& d = out[0];
    d.name = "visual odometry";
    std::snprintf(buf, sizeof buf, "%s %s", cfg.hardware.camera.device.c_str(), cfg.hardware.camera.frame.c_str());
    d.hardware_id = buf;
    describe_keys(d, kVoKeys);
  }

  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses&, std::string* error) const override {
    if (ctx.host == nullptr || ctx.host->frame_source() == nullptr) {
      *error = "[vo] needs the camera's frames, and no camera was made";
      return nullptr;
    }
    return VisualOdometryDevice::create(*ctx.host->frame_source(), ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& visual_odometry_descriptor() noexcept {
  static const VisualOdometryDescriptor d;
  return d;
}

}  // namespace rtfuse
