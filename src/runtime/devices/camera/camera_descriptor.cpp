#include "runtime/devices/camera/camera_descriptor.hpp"

#include <cstdio>

#include "drivers/camera/camera_modes.hpp"
#include "drivers/camera/zed_usb_hint.hpp"
#include "hal/linux/v4l2_stream.hpp"
#include "runtime/devices/camera/camera_calibration.hpp"
#include "runtime/devices/camera/camera_config.hpp"
#include "runtime/devices/camera/camera_device.hpp"
#include "runtime/devices/device_registry.hpp"

namespace rtfuse {
namespace {

class CameraDescriptor final : public DeviceDescriptor {
 public:
  const char* name() const noexcept override { return "camera"; }
  // Paced by the sensor's frame rate, and its pairs' consumers run there too.
  DeviceScheduling scheduling() const noexcept override { return DeviceScheduling::kThread; }
  std::vector<std::string_view> sections() const override { return {"camera"}; }
  void read_config(const config::Section& root, RuntimeConfig& cfg) const override {
    config::read_camera_config(root, cfg);
  }
  bool enabled(const RuntimeConfig& cfg) const noexcept override { return cfg.hardware.camera.enabled; }

  // The factory calibration is read once: the driver and the recording then
  // hold the same bytes, and a replay takes them from the recording.
  bool prepare(RuntimeConfig& cfg, std::string* error) const override {
    if (resolve_camera_calibration(&cfg.hardware.camera, error)) return true;
    *error = "camera.calibration: " + *error;
    return false;
  }
  void recorded_files(const RuntimeConfig& cfg, std::vector<transport::RecordedFile>* out) const override {
    const CameraSection& c = cfg.hardware.camera;
    if (!c.calibration_text.empty()) out->push_back({kCameraCalibrationKey, c.calibration_file, c.calibration_text});
  }
  void restore_file(const transport::RecordedFile& file, RuntimeConfig& cfg) const override {
    if (file.key == kCameraCalibrationKey) cfg.hardware.camera.calibration_text = file.text;
  }

  std::uint32_t required_buses(const RuntimeConfig&) const noexcept override {
    return bus_bit(BusKind::kVideo) | bus_bit(BusKind::kClock);
  }
  // Its clock only times the back-off while it is unplugged: a replay's
  // free-running clock ends that wait at once.
  bool records_clock() const noexcept override { return false; }
  std::string bus_path(const RuntimeConfig& cfg) const override {
    return std::string(cfg.hardware.camera.device.view());
  }

  bool open_linux(const RuntimeConfig& cfg, BusKeeper& keep, hal::Clock& clock, DeviceBuses* out,
                  std::string* description, std::string* error) const override {
    const CameraSection& c = cfg.hardware.camera;
    drivers::CameraMode mode;
    if (!drivers::find_camera_mode(c.resolution.view(), c.fps, &mode, error)) return false;
    hal::VideoRequest req;
    req.pixel_format = hal::kFourccYuyv;
    req.width = drivers::side_by_side_width(mode);
    req.height = drivers::side_by_side_height(mode);
    req.fps = c.fps;
    req.buffers = c.buffers;
    hal::V4l2OpenFailure failure;
    out->video = keep.keep(hal::V4l2Stream::open(c.device.c_str(), req, error, &failure));
    if (out->video == nullptr) {
      // A ZED on USB 2 offers VGA only; the refusal alone does not say so.
      *error += drivers::zed_usb2_hint(mode, failure.given, failure.offered);
      return false;
    }
    out->clock = &clock;
    *description += "camera: V4L2 mmap streaming\n";
    return true;
  }

  int slot_count(const RuntimeConfig&) const noexcept override { return 1; }
  void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept override {
    const CameraSection& c = cfg.hardware.camera;
    char buf[160];
    DeviceStatus& d = out[0];
    d.name = "camera";
    std::snprintf(buf, sizeof buf, "%s %s@%d", c.device.c_str(), c.resolution.c_str(), c.fps);
    d.hardware_id = buf;
    describe_keys(d, kCameraKeys);
  }

  std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses& buses,
                                 std::string* error) const override {
    return CameraDevice::create(buses, ctx.core, ctx.first_slot, hosts_consumers(ctx.core.config()), error);
  }

 private:
  // A registered consumer of its pairs is configured (the visual odometry).
  bool hosts_consumers(const RuntimeConfig& cfg) const noexcept {
    for (int i = 0; i < device_type_count(); ++i) {
      const DeviceDescriptor& d = device_type(i);
      if (d.host() != nullptr && std::string_view(d.host()) == name() && d.enabled(cfg)) return true;
    }
    return false;
  }
};

}  // namespace

const DeviceDescriptor& camera_descriptor() noexcept {
  static const CameraDescriptor d;
  return d;
}

}  // namespace rtfuse
