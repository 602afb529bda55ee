#include "runtime/devices/wheel_encoders/wheel_encoders_descriptor.hpp"

#include <cstdio>

#include "hal/linux/socketcan_bus.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoder_device.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoders_config.hpp"

namespace rtfuse {
namespace {

// The odometry has a slot (and runs) only when a sensor fuses it.
bool fuses_wheels(const RuntimeConfig& cfg) noexcept { return source_sensor(cfg, "wheel_odometry") >= 0; }

class WheelEncodersDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "wheel_encoders"; }
  // On the loop's own thread: SYNC and TPDOs keep time with the tick.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kPolled; }
  std::vector<std::string_view> sections() const override { return {"can", "wheel_odometry"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_wheel_encoders_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override { return cfg.hardware.can.enabled; }
  std::vector<DeviceSource> sources() const override {
    return {{"wheel_odometry", est::SensorKind::kTwist, "twist", "wheel_odometry"}};
  }
  std::uint32_t required_buses(const RuntimeConfig&) const noexcept override { return bus_bit(BusKind::kCan); }
  std::string bus_path(const RuntimeConfig& cfg) const override { return std::string(cfg.hardware.can.interface.view()); }

  bool open_linux(const RuntimeConfig& cfg, BusKeeper& keep, hal::Clock&, DeviceBuses* out, std::string* description,
                  std::string* error) const override {
    const CanSection& can = cfg.hardware.can;
    std::uint32_t ids[3 * kMaxWheelNodes];
    const int n = encoder_can_ids(can, ids, 3 * kMaxWheelNodes);
    hal::CanIdFilter filters[3 * kMaxWheelNodes];
    for (int i = 0; i < n; ++i) filters[i] = hal::CanIdFilter{ids[i], 0x7FF, false};
    hal::SocketCanBus* bus = keep.keep(hal::SocketCanBus::open(can.interface.c_str(), filters, n, error));
    if (bus == nullptr) return false;
    out->can = bus;
    *description += "CAN bus " + bus->name() + ": SocketCAN raw, kernel receive stamps\n";
    return true;
  }

  int slot_count(const RuntimeConfig& cfg) const noexcept override {
    return 1 + cfg.hardware.can.num_nodes + (fuses_wheels(cfg) ? 1 : 0);
  }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    const CanSection& can = cfg.hardware.can;
    char buf[160];
    DeviceStatus& bus = out[0];
    bus.name = "can bus";
    bus.hardware_id = can.interface.c_str();
    describe_keys(bus, kCanBusKeys);
    for (int n = 0; n < can.num_nodes; ++n) {
      const CanNodeSection& node = can.nodes[static_cast<std::size_t>(n)];
      DeviceStatus& e = out[1 + n];
      std::snprintf(buf, sizeof buf, "wheel %s node %d", node.side == WheelSideConfig::kLeft ? "left" : "right",
                    node.node_id);
      e.name = buf;
      std::snprintf(buf, sizeof buf, "%s node 0x%02X", can.interface.c_str(), node.node_id);
      e.hardware_id = buf;
      describe_keys(e, kEncoderNodeKeys);
    }
    if (fuses_wheels(cfg)) {
      DeviceStatus& d = out[1 + can.num_nodes];
      d.name = "wheel odometry";
      d.hardware_id = can.interface.c_str();
      describe_keys(d, kWheelOdometryKeys);
    }
  }

  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses& buses,
                                 std::string* error) const override {
    return WheelEncoderDevice::create(*buses.can, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& wheel_encoders_descriptor() noexcept {
  static const WheelEncodersDescriptor d;
  return d;
}

int encoder_can_ids(const CanSection& can, std::uint32_t* ids, int max) {
  int n = 0;
  for (int i = 0; i < can.num_nodes; ++i) {
    const CanNodeSection& node = can.nodes[static_cast<std::size_t>(i)];
    const std::uint32_t tpdo = node.tpdo_cob_id != 0 ? node.tpdo_cob_id : 0x180u + node.node_id;
    for (std::uint32_t id : {tpdo, 0x700u + node.node_id, 0x080u + node.node_id}) {
      if (n < max) ids[n++] = id;
    }
  }
  return n;
}

}  // namespace rtfuse
