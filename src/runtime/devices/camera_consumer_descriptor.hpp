#pragma once
// What the descriptors of the camera's frame consumers (the visual
// odometry, the mapper) share: the camera as their host and bus path, one
// diagnostics slot named with the camera's device, and the camera's frame
// source taken from the context, or an error naming their section.
#include <cstdio>
#include <string>

#include "runtime/devices/device_descriptor.hpp"
#include "runtime/devices/frame_consumer.hpp"

namespace rtfuse {

class CameraConsumerDescriptor : public DeviceDescriptor {
 public:
  const char* host() const noexcept override { return "camera"; }
  std::string bus_path(const RuntimeConfig& cfg) const override {
    return std::string(cfg.hardware.camera.device.view());
  }
  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }

 protected:
  // The slot's name, and its hardware id: the camera's device and `detail`.
  template <std::size_t N>
  static void describe_slot(const RuntimeConfig& cfg, DeviceStatus& d, const char* name, const char* detail,
                            const char* const (&keys)[N]) noexcept {
    char buf[160];
    d.name = name;
    std::snprintf(buf, sizeof buf, "%s %s", cfg.hardware.camera.device.c_str(), detail);
    d.hardware_id = buf;
    describe_keys(d, keys);
  }
  // The camera's pairs, or null with *error: "[section] needs the camera's
  // frames".
  static FrameSource* camera_of(const DeviceContext& ctx, const char* section, std::string* error) {
    if (ctx.host != nullptr && ctx.host->frame_source() != nullptr) return ctx.host->frame_source();
    *error = std::string("[") + section + "] needs the camera's frames, and no camera was made";
    return nullptr;
  }
};

}  // namespace rtfuse
