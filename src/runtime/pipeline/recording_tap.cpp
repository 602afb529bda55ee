#include "runtime/pipeline/recording_tap.hpp"

#include <algorithm>

namespace rtfuse {
namespace {

transport::DeviceKind recorded_kind(BusKind k) noexcept {
  switch (k) {
    case BusKind::kCan: return transport::DeviceKind::kCan;
    case BusKind::kI2c: return transport::DeviceKind::kI2c;
    case BusKind::kEdge: return transport::DeviceKind::kGpioEdge;
    case BusKind::kVideo: return transport::DeviceKind::kVideo;
    case BusKind::kSerial: return transport::DeviceKind::kSerial;
    case BusKind::kClock: break;
  }
  return transport::DeviceKind::kClock;
}

// The kinds of a device's buses that go into the recording, in table order.
std::uint32_t recorded_buses(const DeviceDescriptor& d, const DeviceBuses& b) noexcept {
  std::uint32_t kinds = b.present();
  // A clock alone is no device's traffic, and some clocks decide nothing.
  if (!d.records_clock() || kinds == bus_bit(BusKind::kClock)) kinds &= ~bus_bit(BusKind::kClock);
  return kinds;
}

}  // namespace

const char* recording_stream(const DeviceDescriptor& d) noexcept {
  return d.scheduling() == DeviceScheduling::kPolled ? kLoopStream : d.name();
}

std::string recorded_bus_name(const DeviceDescriptor& d, const RuntimeConfig& cfg, BusKind kind) {
  switch (kind) {
    case BusKind::kEdge: return std::string(d.name()) + "-drdy";
    case BusKind::kClock: return std::string(d.name()) + "-clock";
    default: return device_path_name(d.bus_path(cfg), d.name());
  }
}

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
  info.streams = {kLoopStream};
  // Each device's buses: its stream and its entries in the device table.
  struct Tapped {
    int device;   // registry index
    int stream;
    int entry[kBusKinds];
  };
  std::vector<Tapped> tapped;
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(cfg)) continue;
    // The files a replay needs (the camera's calibration) travel along.
    d.recorded_files(cfg, &info.files);
    const std::uint32_t kinds = recorded_buses(d, inner.device[i]);
    if (kinds == 0) continue;
    Tapped tap{i, 0, {-1, -1, -1, -1, -1, -1}};
    if (d.scheduling() != DeviceScheduling::kPolled) {
      tap.stream = static_cast<int>(info.streams.size());
      info.streams.push_back(d.name());
    }
    for (int k = 0; k < kBusKinds; ++k) {
      if ((kinds & (1u << k)) == 0) continue;
      const auto kind = static_cast<BusKind>(k);
      info.devices.push_back({recorded_bus_name(d, cfg, kind), recorded_kind(kind), tap.stream});
      tap.entry[k] = static_cast<int>(info.devices.size()) - 1;
    }
    tapped.push_back(tap);
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
  t->buses_ = inner;
  for (const Tapped& tap : tapped) {
    const DeviceBuses& in = inner.device[tap.device];
    DeviceBuses& out = t->buses_.device[tap.device];
    auto index = [&](BusKind k) { return static_cast<std::uint8_t>(tap.entry[static_cast<int>(k)]); };
    auto has = [&](BusKind k) { return tap.entry[static_cast<int>(k)] >= 0; };
    if (has(BusKind::kCan)) {
      t->cans_.push_back(std::make_unique<hal::RecordingCanBus>(*in.can, r.ring(tap.stream), index(BusKind::kCan), &clock));
      out.can = t->cans_.back().get();
    }
    if (has(BusKind::kI2c)) {
      t->i2cs_.push_back(std::make_unique<hal::RecordingI2cBus>(*in.i2c, r.ring(tap.stream), index(BusKind::kI2c), &clock));
      out.i2c = t->i2cs_.back().get();
    }
    if (has(BusKind::kEdge)) {
      t->edges_.push_back(
          std::make_unique<hal::RecordingEdgeSource>(*in.edge, r.ring(tap.stream), index(BusKind::kEdge), &clock));
      out.edge = t->edges_.back().get();
    }
    if (has(BusKind::kVideo)) {
      // Eight frames (a quarter of a second at 30 fps) ride out a disk that
      // stalls; beyond that the camera thread drops records, never waits.
      hal::VideoRecordRing* ring = r.add_video_ring(tap.stream, in.video->format().image_size, 8, 0, error);
      if (ring == nullptr) return nullptr;
      t->videos_.push_back(std::make_unique<hal::RecordingVideoStream>(*in.video, *ring, index(BusKind::kVideo), &clock));
      out.video = t->videos_.back().get();
    }
    if (has(BusKind::kSerial)) {
      t->serials_.push_back(
          std::make_unique<hal::RecordingSerialPort>(*in.serial, r.ring(tap.stream), index(BusKind::kSerial), &clock));
      out.serial = t->serials_.back().get();
    }
    if (has(BusKind::kClock)) {
      t->clocks_.push_back(std::make_unique<hal::RecordingClock>(*in.clock, r.ring(tap.stream), index(BusKind::kClock)));
      out.clock = t->clocks_.back().get();
    }
  }
  return t;
}

std::int64_t RecordingTap::overflows() const {
  std::int64_t n = 0;
  for (const auto& b : cans_) n += b->overflows();
  for (const auto& b : i2cs_) n += b->overflows();
  for (const auto& b : edges_) n += b->overflows();
  for (const auto& b : videos_) n += b->overflows();
  for (const auto& b : serials_) n += b->overflows();
  for (const auto& b : clocks_) n += b->overflows();
  return n;
}

}  // namespace rtfuse
