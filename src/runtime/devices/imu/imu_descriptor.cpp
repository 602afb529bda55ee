#include "runtime/devices/imu/imu_descriptor.hpp"

#include <cstdio>

#include "hal/linux/gpiod_line.hpp"
#include "hal/linux/i2c_dev_bus.hpp"
#include "runtime/devices/imu/imu_device.hpp"
#include "runtime/devices/imu/mpu_config.hpp"

namespace rtfuse {
namespace {

class ImuDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "imu"; }
  // Woken by the chip's data-ready edge, not by the loop's tick.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kThread; }
  std::vector<std::string_view> sections() const override { return {"mpu"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_mpu_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override { return cfg.hardware.mpu.enabled; }
  std::vector<DeviceSource> sources() const override { return {{"mpu", est::SensorKind::kImu, "imu", "mpu"}}; }
  std::uint32_t required_buses(const RuntimeConfig&) const noexcept override {
    return bus_bit(BusKind::kI2c) | bus_bit(BusKind::kClock);
  }
  std::string bus_path(const RuntimeConfig& cfg) const override { return std::string(cfg.hardware.mpu.device.view()); }

  bool open_linux(const RuntimeConfig& cfg, BusKeeper& keep, hal::Clock& clock, DeviceBuses* out,
                  std::string* description, std::string* error) const override {
    const MpuSection& m = cfg.hardware.mpu;
    hal::I2cDevBus* i2c = keep.keep(hal::I2cDevBus::open(m.device.c_str(), hal::I2cRetryPolicy{}, error));
    if (i2c == nullptr) return false;
    out->i2c = i2c;
    out->clock = &clock;
    // An SMBus-only adapter works but reads long bursts in pieces: the user should know.
    *description += "IMU bus " + i2c->name() + ": " + hal::to_string(i2c->mode()) + "\n";
    if (m.data_ready_chip.empty()) {
      *description += "IMU data-ready: none, polled at the sample rate\n";
      return true;
    }
    out->edge = keep.keep(hal::GpiodEdgeSource::open(m.data_ready_chip.c_str(),
                                                     static_cast<unsigned>(m.data_ready_line), hal::EdgeKind::kRising,
                                                     error));
    if (out->edge == nullptr) return false;
    *description += "IMU data-ready: GPIO rising edges, kernel-stamped\n";
    return true;
  }

  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    char buf[160];
    DeviceStatus& d = out[0];
    d.name = "imu";
    std::snprintf(buf, sizeof buf, "%s 0x%02X", cfg.hardware.mpu.device.c_str(), cfg.hardware.mpu.address);
    d.hardware_id = buf;
    describe_keys(d, kImuKeys);
  }

  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses& buses,
                                 std::string* error) const override {
    return ImuDevice::create(buses, ctx.core, ctx.first_slot, error);
  }
};

}  // namespace

const DeviceDescriptor& imu_descriptor() noexcept {
  static const ImuDescriptor d;
  return d;
}

}  // namespace rtfuse
