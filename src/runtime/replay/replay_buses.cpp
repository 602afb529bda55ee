#include "runtime/replay/replay_buses.hpp"

#include "hal/replay/replay_can_bus.hpp"
#include "hal/replay/replay_clock.hpp"
#include "hal/replay/replay_gpio.hpp"
#include "hal/replay/replay_i2c_bus.hpp"
#include "hal/replay/replay_serial_port.hpp"
#include "runtime/pipeline/recording_tap.hpp"

namespace rtfuse {
namespace {

int stream_index(const transport::RecordingInfo& info, std::string_view name) {
  for (std::size_t i = 0; i < info.streams.size(); ++i) {
    if (info.streams[i] == name) return static_cast<int>(i);
  }
  return -1;
}

// The bus kind a recorded device entry stands for (false: none a device takes).
bool bus_kind(transport::DeviceKind k, BusKind* out) {
  switch (k) {
    case transport::DeviceKind::kCan: *out = BusKind::kCan; return true;
    case transport::DeviceKind::kI2c: *out = BusKind::kI2c; return true;
    case transport::DeviceKind::kGpioEdge: *out = BusKind::kEdge; return true;
    case transport::DeviceKind::kVideo: *out = BusKind::kVideo; return true;
    case transport::DeviceKind::kSerial: *out = BusKind::kSerial; return true;
    case transport::DeviceKind::kClock: *out = BusKind::kClock; return true;
    case transport::DeviceKind::kGpioOutput: return false;
  }
  return false;
}

std::string bus_list(std::uint32_t kinds) {
  std::string out;
  for (int k = 0; k < kBusKinds; ++k) {
    if ((kinds & (1u << k)) == 0) continue;
    if (!out.empty()) out += ", ";
    out += to_string(static_cast<BusKind>(k));
  }
  return out;
}

}  // namespace

std::unique_ptr<ReplayBuses> ReplayBuses::bind(const HalRecording& rec, const RuntimeConfig& cfg,
                                               std::string* error) {
  std::unique_ptr<ReplayBuses> r(new ReplayBuses());
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(cfg)) continue;
    DeviceBuses& b = r->buses_.device[i];
    ReplayedDevice& rd = r->devices_[i];
    const char* stream_name = recording_stream(d);
    const int s = stream_index(rec.info, stream_name);
    if (s >= 0) {
      hal::replay::ReplayStream& stream = *rec.streams[static_cast<std::size_t>(s)];
      rd.stream = &stream;
      for (std::size_t e = 0; e < rec.info.devices.size(); ++e) {
        const transport::RecordedDevice& dev = rec.info.devices[e];
        BusKind kind = BusKind::kCan;
        if (dev.stream != s || !bus_kind(dev.kind, &kind) || (b.present() & bus_bit(kind)) != 0) continue;
        // Two polled devices share the loop's stream: their names tell them apart.
        if (dev.name != recorded_bus_name(d, cfg, kind)) continue;
        const auto index = static_cast<std::uint8_t>(e);
        switch (kind) {
          case BusKind::kCan: b.can = r->keep_.keep(std::make_unique<hal::replay::ReplayCanBus>(stream, index)); break;
          case BusKind::kI2c: b.i2c = r->keep_.keep(std::make_unique<hal::replay::ReplayI2cBus>(stream, index)); break;
          case BusKind::kEdge:
            b.edge = r->keep_.keep(std::make_unique<hal::replay::ReplayEdgeSource>(stream, index));
            break;
          case BusKind::kSerial:
            b.serial = r->keep_.keep(std::make_unique<hal::replay::ReplaySerialPort>(stream, index));
            break;
          case BusKind::kClock: b.clock = r->keep_.keep(std::make_unique<hal::replay::ReplayClock>(stream, index)); break;
          case BusKind::kVideo:
            if (static_cast<std::size_t>(s) < rec.videos.size() && rec.videos[static_cast<std::size_t>(s)]) {
              rd.video = rec.videos[static_cast<std::size_t>(s)].get();
              b.video = r->keep_.keep(std::make_unique<hal::replay::ReplayVideoStream>(*rd.video, index));
            }
            break;
        }
      }
    }
    // A device that needs a clock nobody recorded (records_clock() false).
    if (b.clock == nullptr && !b.empty() && (d.required_buses(cfg) & bus_bit(BusKind::kClock)) != 0) {
      r->clocks_.push_back(std::make_unique<FreeRunningClock>());
      rd.free_clock = r->clocks_.back().get();
      b.clock = rd.free_clock;
    }
    const std::uint32_t missing = d.required_buses(cfg) & ~b.present();
    if (missing != 0) {
      *error = "the configuration has [" + std::string(d.sections().front()) + "] but the recording has no " +
               bus_list(missing) + " of stream '" + stream_name + "'";
      return nullptr;
    }
  }
  return r;
}

const ReplayedDevice& ReplayBuses::device(std::string_view name) const {
  static const ReplayedDevice none;
  const int i = find_device_type(name);
  return i < 0 ? none : devices_[i];
}

}  // namespace rtfuse
