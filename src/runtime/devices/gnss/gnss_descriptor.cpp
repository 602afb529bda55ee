#include "runtime/devices/gnss/gnss_descriptor.hpp"

#include <cstdio>

#include "hal/linux/termios_serial_port.hpp"
#include "runtime/devices/gnss/gnss_config.hpp"
#include "runtime/devices/gnss/gnss_device.hpp"

namespace rtfuse {
namespace {

class GnssDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "gnss"; }
  // Waits on the port for the receiver's bytes, whenever they come.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kThread; }
  std::vector<std::string_view> sections() const override { return {"gnss"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_gnss_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override { return cfg.hardware.gnss.enabled; }
  std::vector<DeviceSource> sources() const override {
    return {{"gnss", est::SensorKind::kNavSatFix, "navsat", "gnss"}};
  }
  std::uint32_t required_buses(const RuntimeConfig&) const noexcept override {
    return bus_bit(BusKind::kSerial) | bus_bit(BusKind::kClock);
  }
  std::string bus_path(const RuntimeConfig& cfg) const override { return std::string(cfg.hardware.gnss.device.view()); }

  bool open_linux(const RuntimeConfig& cfg, BusKeeper& keep, hal::Clock& clock, DeviceBuses* out,
                  std::string* description, std::string* error) const override {
    const GnssSection& g = cfg.hardware.gnss;
    hal::TermiosSerialPort* port = keep.keep(hal::TermiosSerialPort::open(g.device.c_str(), g.baud, error));
    if (port == nullptr) return false;
    out->serial = port;
    out->clock = &clock;
    *description += "GNSS receiver " + port->path() + ": termios raw at " + std::to_string(port->baud()) +
                    " baud, stamped at read\n";
    return true;
  }

  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    const GnssSection& g = cfg.hardware.gnss;
    char buf[160];
    DeviceStatus& d = out[0];
    d.name = "gnss";
    std::snprintf(buf, sizeof buf, "%s %s@%d", g.device.c_str(), g.protocol == GnssProtocolConfig::kUbx ? "ubx" : "nmea",
                  g.baud);
    d.hardware_id = buf;
    describe_keys(d, kGnssKeys);
  }

  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses& buses,
                                 std::string* error) const override {
    return GnssDevice::create(buses, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& gnss_descriptor() noexcept {
  static const GnssDescriptor d;
  return d;
}

}  // namespace rtfuse
