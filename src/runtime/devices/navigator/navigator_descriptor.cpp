#include "runtime/devices/navigator/navigator_descriptor.hpp"

#include "runtime/devices/grid_consumer.hpp"
#include "runtime/devices/navigator/navigation_config.hpp"
#include "runtime/devices/navigator/navigator_device.hpp"

namespace rtfuse {
namespace {

class NavigatorDescriptor final : public DeviceDescriptor {
 public:
  // Its thread plans (the architecture's planner thread); thread names
  // have 15 characters, so "rtfuse-planner".
  const char* name() const noexcept override { return "planner"; }
  // A plan can take milliseconds: never on the loop.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kWorker; }
  const char* host() const noexcept override { return "mapper"; }
  std::vector<std::string_view> sections() const override { return {"navigation"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_navigation_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override {
    return cfg.hardware.camera.enabled && cfg.hardware.mapping.enabled && cfg.hardware.navigation.enabled;
  }
  std::vector<std::string> input_channels(const RuntimeConfig& cfg) const override {
    // NavigatorDevice::Input's order.
    return {std::string(cfg.hardware.navigation.goal_channel.view()),
            std::string(cfg.hardware.navigation.stop_channel.view())};
  }
  std::string bus_path(const RuntimeConfig&) const override { return "navigator"; }
  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    // The hardware id says whether this process may move the robot.
    const char* id = cfg.hardware.navigation.follow ? "planner + follower" : "planner (follow = false)";
    out[0].name = "navigator";
    out[0].hardware_id = id;
    describe_keys(out[0], kNavigatorKeys);
  }
  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses&, std::string* error) const override {
    GridSource* grids = ctx.host != nullptr ? ctx.host->grid_source() : nullptr;
    if (grids == nullptr) {
      *error = "[navigation] needs the mapper's grid, and no mapper was made";
      return nullptr;
    }
    return NavigatorDevice::create(*grids, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& navigator_descriptor() noexcept {
  static const NavigatorDescriptor d;
  return d;
}

}  // namespace rtfuse
