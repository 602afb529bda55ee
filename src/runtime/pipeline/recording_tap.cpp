#include "runtime/pipeline/recording_tap.hpp"

#include <algorithm>

#include "runtime/devices/camera/camera_calibration.hpp"

namespace rtfuse {
namespace {

// Channel-safe: "/dev/i2c-1" -> "i2c-1", no '/' or spaces.
std::string device_name(std::string_view path, const char* fallback) {
  const std::size_t slash = path.rfind('/');
  std::string name(slash == std::string_view::npos ? path : path.substr(slash + 1));
  std::replace(name.begin(), name.end(), ' ', '_');
  return name.empty() ? std::string(fallback) : name;
}

}  // namespace

std::string can_device_name(const RuntimeConfig& cfg) {
  return device_name(cfg.hardware.can.interface.view(), "can");
}
std::string i2c_device_name(const RuntimeConfig& cfg) { return device_name(cfg.hardware.mpu.device.view(), "i2c"); }
std::string video_device_name(const RuntimeConfig& cfg) {
  return device_name(cfg.hardware.camera.device.view(), "video");
}
std::string gnss_device_name(const RuntimeConfig& cfg) { return device_name(cfg.hardware.gnss.device.view(), "gnss"); }

RecordingTap::~RecordingTap() = default;

std::unique_ptr<RecordingTap> RecordingTap::create(const std::string& path, const RuntimeConfig& cfg,
                                                   const std::string& config_text, const HalBuses& inner,
                                                   hal::Clock& clock, TimeNs start_ns, std::string* error) {
  std::unique_ptr<RecordingTap> t(new RecordingTap());
  transport::RecordingInfo info;
  info.rtfuse_version = "rtfuse " RTFUSE_VERSION;
  info.start_ns = start_ns;
  info.config_path = cfg.source;
  info.config_text = config_text;
  info.config_hash = transport::config_text_hash(config_text);
  info.streams = {kLoopStream, kImuStream};
  // The calibration travels with the recording: its replay needs no file.
  const CameraSection& camera_section = cfg.hardware.camera;
  if (camera_section.enabled && !camera_section.calibration_text.empty()) {
    info.files.push_back({kCameraCalibrationKey, camera_section.calibration_file, camera_section.calibration_text});
  }
  // The camera's calls go through a ring of their own (frames are large), on
  // a stream of their own; a configuration without one records as before.
  if (inner.camera.video != nullptr) info.streams.push_back(kCameraStream);
  int can = -1, i2c = -1, drdy = -1, imu_clock = -1;
  auto add = [&info](std::string name, transport::DeviceKind kind, int stream) {
    info.devices.push_back({std::move(name), kind, stream});
    return static_cast<int>(info.devices.size()) - 1;
  };
  if (inner.can != nullptr) can = add(can_device_name(cfg), transport::DeviceKind::kCan, 0);
  if (inner.imu.i2c != nullptr) i2c = add(i2c_device_name(cfg), transport::DeviceKind::kI2c, 1);
  if (inner.imu.data_ready != nullptr) drdy = add("imu-drdy", transport::DeviceKind::kGpioEdge, 1);
  if (inner.imu.clock != nullptr && inner.imu.i2c != nullptr) {
    imu_clock = add("imu-clock", transport::DeviceKind::kClock, 1);
  }
  const int camera = inner.camera.video != nullptr ? add(video_device_name(cfg), transport::DeviceKind::kVideo, 2) : -1;
  int gnss = -1, gnss_clock = -1, gnss_stream = -1;
  if (inner.gnss.serial != nullptr && inner.gnss.clock != nullptr) {
    gnss_stream = static_cast<int>(info.streams.size());
    info.streams.push_back(kGnssStream);
    gnss = add(gnss_device_name(cfg), transport::DeviceKind::kSerial, gnss_stream);
    gnss_clock = add("gnss-clock", transport::DeviceKind::kClock, gnss_stream);
  }
  runtime::RecorderRingSizes sizes;
  // A second of the loop at 1 kHz and of a 1 kHz IMU, so a writer stalled
  // by the disk for that long loses nothing.
  sizes.bus_events = 8192;
  sizes.ticks = 2048;
  sizes.outputs = 512;
  t->recorder_ = runtime::Recorder::create(path, info, sizes, error);
  if (!t->recorder_) return nullptr;
  runtime::Recorder& r = *t->recorder_;
  HalBuses& b = t->buses_;
  if (can >= 0) {
    t->can_ = std::make_unique<hal::RecordingCanBus>(*inner.can, r.ring(0), static_cast<std::uint8_t>(can), &clock);
    b.can = t->can_.get();
  }
  if (i2c >= 0) {
    t->i2c_ = std::make_unique<hal::RecordingI2cBus>(*inner.imu.i2c, r.ring(1), static_cast<std::uint8_t>(i2c), &clock);
    b.imu.i2c = t->i2c_.get();
  }
  if (drdy >= 0) {
    t->drdy_ =
        std::make_unique<hal::RecordingEdgeSource>(*inner.imu.data_ready, r.ring(1), static_cast<std::uint8_t>(drdy), &clock);
    b.imu.data_ready = t->drdy_.get();
  }
  if (imu_clock >= 0) {
    t->imu_clock_ =
        std::make_unique<hal::RecordingClock>(*inner.imu.clock, r.ring(1), static_cast<std::uint8_t>(imu_clock));
    b.imu.clock = t->imu_clock_.get();
  }
  if (camera >= 0) {
    // Eight frames (a quarter of a second at 30 fps) ride out a disk that
    // stalls; beyond that the camera thread drops records, never waits.
    hal::VideoRecordRing* ring = r.add_video_ring(2, inner.camera.video->format().image_size, 8, 0, error);
    if (ring == nullptr) return nullptr;
    t->camera_ = std::make_unique<hal::RecordingVideoStream>(*inner.camera.video, *ring,
                                                             static_cast<std::uint8_t>(camera), &clock);
    b.camera.video = t->camera_.get();
    b.camera.clock = inner.camera.clock;
  }
  if (gnss >= 0) {
    t->gnss_ = std::make_unique<hal::RecordingSerialPort>(*inner.gnss.serial, r.ring(gnss_stream),
                                                          static_cast<std::uint8_t>(gnss), &clock);
    t->gnss_clock_ = std::make_unique<hal::RecordingClock>(*inner.gnss.clock, r.ring(gnss_stream),
                                                           static_cast<std::uint8_t>(gnss_clock));
    b.gnss.serial = t->gnss_.get();
    b.gnss.clock = t->gnss_clock_.get();
  }
  return t;
}

std::int64_t RecordingTap::overflows() const {
  std::int64_t n = 0;
  if (can_) n += can_->overflows();
  if (i2c_) n += i2c_->overflows();
  if (drdy_) n += drdy_->overflows();
  if (imu_clock_) n += imu_clock_->overflows();
  if (camera_) n += camera_->overflows();
  if (gnss_) n += gnss_->overflows();
  if (gnss_clock_) n += gnss_clock_->overflows();
  return n;
}

}  // namespace rtfuse
