#include "runtime/replay/hal_replay.hpp"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <map>
#include <vector>

#include "hal/replay/replay_can_bus.hpp"
#include "hal/replay/replay_clock.hpp"
#include "hal/replay/replay_gpio.hpp"
#include "hal/replay/replay_i2c_bus.hpp"
#include "hal/replay/replay_serial_port.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "runtime/devices/camera/camera_calibration.hpp"
#include "runtime/pipeline/recording_tap.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"

namespace rtfuse {
namespace {

std::string hex64(std::int64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// Writes the replay's outputs and compares the estimate messages with the
// recorded ones, channel by channel in publishing order.
class CompareSink final : public MessageSink {
 public:
  // Only the estimate channels are compared: other recorded channels (the
  // simulator's ground truth) are not the publisher's.
  CompareSink(const HalRecording& rec, const RuntimeConfig& cfg, transport::EventLogWriter* out)
      : diagnostics_(cfg.publish.diagnostics_channel.view()), out_(out) {
    const std::string estimate[] = {std::string(cfg.publish.odometry_channel.view()),
                                    std::string(cfg.publish.pose_channel.view()),
                                    std::string(cfg.publish.tf_channel.view()),
                                    std::string(cfg.publish.state_channel.view()),
                                    std::string(cfg.hardware.wheel_odometry.raw_channel.view())};
    for (const RecordedOutput& o : rec.outputs) {
      if (std::find(std::begin(estimate), std::end(estimate), o.channel) != std::end(estimate)) {
        recorded_[o.channel].push_back(&o);
      }
    }
  }

  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) override {
    ++published;
    if (out_ != nullptr && !out_->write(ns_to_utime(now), channel, data, static_cast<std::size_t>(size), &error)) {
      return false;
    }
    if (diagnostics_ == channel) return true;
    auto it = recorded_.find(channel);
    std::size_t& next = next_[channel];
    if (it == recorded_.end() || next >= it->second.size()) return true;  // beyond the recording
    const RecordedOutput& r = *it->second[next++];
    ++compared;
    if (r.bytes.size() == static_cast<std::size_t>(size) && std::equal(r.bytes.begin(), r.bytes.end(), data)) {
      ++identical;
    } else if (first_mismatch.empty()) {
      first_mismatch = "'" + std::string(channel) + "' message " + std::to_string(next - 1) + " (log event " +
                       std::to_string(r.event_number) + "): " + std::to_string(r.bytes.size()) +
                       " bytes recorded, the replay's " + std::to_string(size) + " bytes differ";
    }
    return true;
  }

  std::int64_t not_reproduced() const {
    std::int64_t n = 0;
    for (const auto& [channel, list] : recorded_) {
      auto it = next_.find(channel);
      const std::size_t used = it == next_.end() ? 0 : it->second;
      n += static_cast<std::int64_t>(list.size() - used);
    }
    return n;
  }

  std::int64_t published = 0, compared = 0, identical = 0;
  std::string first_mismatch, error;

 private:
  std::string diagnostics_;
  transport::EventLogWriter* out_;
  std::map<std::string, std::vector<const RecordedOutput*>> recorded_;
  std::map<std::string, std::size_t> next_;
};

// Publishes what the live loop queued at the tick being replayed, no more,
// no fewer; a tick whose bus calls ran past the recording (or off it) did
// not happen as recorded and publishes nothing.
class ReplayOutput final : public OutputStage {
 public:
  ReplayOutput(Publisher& publisher, MessageSink& sink, const HalRecording& rec)
      : publisher_(publisher), sink_(sink), rec_(rec) {}
  void expect(std::uint32_t recorded) { recorded_ = recorded; }
  std::uint32_t deliver(const Snapshot& snap, std::uint32_t, TimeNs now) noexcept override {
    for (const auto& s : rec_.streams) {
      if (s->diverged()) return 0;
    }
    publisher_.publish(snap, recorded_, now, sink_);
    return recorded_;
  }

 private:
  Publisher& publisher_;
  MessageSink& sink_;
  const HalRecording& rec_;
  std::uint32_t recorded_ = 0;
};

// The camera thread's clock is not recorded: its driver reads it only to
// back off while the camera is unplugged. In replay that wait passes at
// once; a recording whose camera was unplugged may therefore diverge at a
// reopen, and says so, but never replays differently in silence.
class FreeRunningClock final : public hal::Clock {
 public:
  TimeNs now() const noexcept override { return now_; }
  void sleep_until(TimeNs t) noexcept override {
    if (t > now_) now_ = t;
  }

 private:
  TimeNs now_ = 0;
};

int stream_index(const transport::RecordingInfo& info, const char* name) {
  for (std::size_t i = 0; i < info.streams.size(); ++i) {
    if (info.streams[i] == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

std::string check_recording_config(const transport::RecordingInfo& info, const std::string& config_text,
                                   const std::string& config_path) {
  const std::int64_t hash = transport::config_text_hash(config_text);
  if (hash == info.config_hash) return "";
  return "the recording was made with another configuration: '" + info.config_path + "' (hash " +
         hex64(info.config_hash) + "), not '" + config_path + "' (hash " + hex64(hash) +
         "); leave out --config to replay with the configuration stored in the recording";
}

HalReplayResult replay_hal_recording(const HalRecording& rec, const RuntimeConfig& given,
                                     transport::EventLogWriter* out,
                                     const std::function<void(const HalReplayProgress&)>& progress) {
  HalReplayResult result;
  // The calibration the camera had, from the recording, not from a file on
  // this machine that may differ or be missing.
  RuntimeConfig cfg = given;
  for (const transport::RecordedFile& f : rec.info.files) {
    if (f.key == kCameraCalibrationKey && cfg.hardware.camera.enabled) cfg.hardware.camera.calibration_text = f.text;
  }
  const int loop = stream_index(rec.info, kLoopStream);
  const int imu = stream_index(rec.info, kImuStream);
  std::vector<std::unique_ptr<hal::CanBus>> cans;
  std::unique_ptr<hal::I2cBus> i2c;
  std::unique_ptr<hal::GpioEdgeSource> drdy;
  std::unique_ptr<hal::Clock> clock;
  const int camera = stream_index(rec.info, kCameraStream);
  const int gnss = stream_index(rec.info, kGnssStream);
  std::unique_ptr<hal::SerialPort> serial;
  std::unique_ptr<hal::Clock> gnss_clock;
  std::unique_ptr<hal::VideoStream> video;
  FreeRunningClock camera_clock;
  HalBuses buses;
  for (std::size_t d = 0; d < rec.info.devices.size(); ++d) {
    const transport::RecordedDevice& dev = rec.info.devices[d];
    hal::replay::ReplayStream& stream = *rec.streams[static_cast<std::size_t>(dev.stream)];
    const auto index = static_cast<std::uint8_t>(d);
    switch (dev.kind) {
      case transport::DeviceKind::kCan:
        if (dev.stream == loop && buses.can == nullptr) {
          cans.push_back(std::make_unique<hal::replay::ReplayCanBus>(stream, index));
          buses.can = cans.back().get();
        }
        break;
      case transport::DeviceKind::kI2c:
        if (dev.stream == imu && !i2c) {
          i2c = std::make_unique<hal::replay::ReplayI2cBus>(stream, index);
          buses.imu.i2c = i2c.get();
        }
        break;
      case transport::DeviceKind::kGpioEdge:
        if (dev.stream == imu && !drdy) {
          drdy = std::make_unique<hal::replay::ReplayEdgeSource>(stream, index);
          buses.imu.data_ready = drdy.get();
        }
        break;
      case transport::DeviceKind::kClock:
        if (dev.stream == imu && !clock) {
          clock = std::make_unique<hal::replay::ReplayClock>(stream, index);
          buses.imu.clock = clock.get();
        } else if (dev.stream == gnss && !gnss_clock) {
          gnss_clock = std::make_unique<hal::replay::ReplayClock>(stream, index);
          buses.gnss.clock = gnss_clock.get();
        }
        break;
      case transport::DeviceKind::kGpioOutput: break;
      case transport::DeviceKind::kSerial:
        if (dev.stream == gnss && !serial) {
          serial = std::make_unique<hal::replay::ReplaySerialPort>(stream, index);
          buses.gnss.serial = serial.get();
        }
        break;
      case transport::DeviceKind::kVideo:
        if (dev.stream == camera && !video && static_cast<std::size_t>(dev.stream) < rec.videos.size() &&
            rec.videos[static_cast<std::size_t>(dev.stream)]) {
          video = std::make_unique<hal::replay::ReplayVideoStream>(*rec.videos[static_cast<std::size_t>(dev.stream)],
                                                                   index);
          buses.camera.video = video.get();
          buses.camera.clock = &camera_clock;
        }
        break;
    }
  }
  const HardwareConfig& hw = cfg.hardware;
  if (hw.can.enabled && buses.can == nullptr) {
    result.error = "the configuration has [can] but the recording has no CAN bus of the loop thread";
    return result;
  }
  if (hw.mpu.enabled && (buses.imu.i2c == nullptr || buses.imu.clock == nullptr)) {
    result.error = "the configuration has [mpu] but the recording has no I2C bus and clock of the IMU thread";
    return result;
  }
  if (hw.camera.enabled && buses.camera.video == nullptr) {
    result.error = "the configuration has [camera] but the recording has no camera stream";
    return result;
  }
  if (hw.gnss.enabled && (buses.gnss.serial == nullptr || buses.gnss.clock == nullptr)) {
    result.error = "the configuration has [gnss] but the recording has no serial port and clock of the GNSS thread";
    return result;
  }
  for (int i = 0; i < cfg.num_sensors; ++i) {
    if (cfg.sensors[static_cast<std::size_t>(i)].source != SensorSource::kLcm) continue;
    for (const transport::LoopTick& t : rec.ticks) {
      if (static_cast<int>(t.consumed.size()) > i && t.consumed[static_cast<std::size_t>(i)] > 0) {
        result.error = "sensor '" + std::string(cfg.sensors[static_cast<std::size_t>(i)].name.view()) +
                       "' took LCM messages during the recording; a HAL recording replays driver inputs only";
        return result;
      }
    }
  }

  std::string err;
  CompareSink sink(rec, cfg, out);
  PipelineOptions options;
  options.sink = &sink;
  std::unique_ptr<TickPipeline> pipeline = TickPipeline::create(cfg, buses, options, &err);
  if (!pipeline) {
    result.error = err;
    return result;
  }
  auto diverged = [&]() -> const hal::replay::ReplayStream* {
    for (const auto& s : rec.streams) {
      if (s->diverged()) return s.get();
    }
    return nullptr;
  };
  ReplayOutput output(pipeline->publisher(), pipeline->sink(), rec);
  // A different call is a divergence; running out of recorded calls (a
  // truncated recording, a ring that overflowed) ends the replay early.
  auto stop_diverged = [&](const hal::replay::ReplayStream& s) {
    if (s.divergence_kind() == hal::replay::DivergenceKind::kMismatch) {
      result.diverged = true;
      result.error = "replay diverged from the recording in stream '" + s.name() + "': " + s.divergence();
    } else {
      result.ended_early = true;
      result.note = "the recording of stream '" + s.name() + "' ends before its last tick: " + s.divergence();
    }
  };

  const TimeNs t0 = rec.info.start_ns != 0 ? rec.info.start_ns : (rec.ticks.empty() ? 0 : rec.ticks.front().time_ns);
  if (!pipeline->start(t0, &err)) {
    if (const auto* s = diverged()) {
      stop_diverged(*s);
    } else {
      result.error = "starting the devices from the recording failed: " + err;
    }
    return result;
  }
  // Each thread device replays the stream named after it; a camera's calls
  // are in the stream's video log.
  const hal::replay::ReplayStream* device_streams[kMaxThreadDevices] = {};
  hal::replay::ReplayVideoLog* device_videos[kMaxThreadDevices] = {};
  for (int d = 0; d < pipeline->thread_device_count(); ++d) {
    const int index = stream_index(rec.info, pipeline->thread_device(d).name());
    if (index < 0) continue;
    device_streams[d] = rec.streams[static_cast<std::size_t>(index)].get();
    // Every stream has a video log; a camera's is the one with a video device.
    const bool has_video = std::any_of(rec.info.devices.begin(), rec.info.devices.end(), [&](const auto& dev) {
      return dev.stream == index && dev.kind == transport::DeviceKind::kVideo;
    });
    if (has_video && static_cast<std::size_t>(index) < rec.videos.size()) {
      device_videos[d] = rec.videos[static_cast<std::size_t>(index)].get();
    }
  }
  auto video_mismatch = [&](int d) {
    const hal::replay::ReplayVideoLog* v = device_videos[d];
    if (v == nullptr || v->divergence_kind() != hal::replay::DivergenceKind::kMismatch) return false;
    result.diverged = true;
    result.error = "replay diverged from the recording in stream '" + std::string(pipeline->thread_device(d).name()) +
                   "': " + v->divergence();
    return true;
  };
  LoopStats loop_stats;
  loop_stats.rate_hz = cfg.rate_hz;
  loop_stats.period_ns = static_cast<std::int64_t>(1e9 / cfg.rate_hz);
  HalReplayProgress prog;
  prog.total_ticks = static_cast<std::int64_t>(rec.ticks.size());
  for (const transport::LoopTick& t : rec.ticks) {
    bool short_of_samples = false;
    for (int d = 0; d < pipeline->thread_device_count() && !short_of_samples; ++d) {
      ThreadDevice& device = pipeline->thread_device(d);
      const hal::replay::ReplayStream* s = device_streams[d];
      const hal::replay::ReplayVideoLog* v = device_videos[d];
      const int sensor = device.sensor();
      if (s == nullptr || sensor < 0 || static_cast<int>(t.consumed.size()) <= sensor) continue;
      const std::int64_t target = t.consumed[static_cast<std::size_t>(sensor)];
      auto more = [&] { return v != nullptr ? !v->diverged() && !v->at_end() : !s->diverged() && !s->at_end(); };
      // The device's thread ran ahead of the loop: replay its calls until
      // the loop has what it took live. A stream that ends or diverges
      // first cannot give more.
      if (v != nullptr && device.samples() < target) camera_clock.sleep_until(t.time_ns);
      while (device.samples() < target && more()) device.step(kDeviceStepTimeoutNs);
      if (video_mismatch(d)) break;
      // Ticking on without the samples the live loop had would publish
      // something it never published: the recording ends here.
      if (device.samples() < target && !s->diverged()) {
        result.ended_early = true;
        result.note = "the recording of stream '" + s->name() + "' ends before tick " + std::to_string(t.seq) +
                      ": it holds " + std::to_string(device.samples()) + " of the " + std::to_string(target) +
                      " " + device.name() + " samples the loop had taken by then";
        short_of_samples = true;
      }
    }
    if (result.diverged) break;
    if (short_of_samples) break;
    if (const auto* s = diverged()) {
      stop_diverged(*s);
      break;
    }
    ++loop_stats.ticks;
    output.expect(t.published);
    pipeline->step(t.time_ns, loop_stats, output);
    if (const auto* s = diverged()) {
      stop_diverged(*s);
      break;
    }
    ++result.ticks;
    ++prog.ticks;
    if (progress && prog.ticks % 10000 == 0) progress(prog);
  }
  // What a camera did after the last sample the loop took (all of it for a
  // camera without odometry) changes no tick: its recorded calls are
  // replayed after the ticks, through the same driver, in their recorded
  // order, so its counters and digest end where the live camera's did.
  for (int d = 0; d < pipeline->thread_device_count() && !result.diverged && !result.ended_early; ++d) {
    ThreadDevice& device = pipeline->thread_device(d);
    if (device_videos[d] == nullptr) continue;
    hal::replay::ReplayVideoLog& log = *device_videos[d];
    camera_clock.sleep_until(t0);
    // Each step makes at least one call unless the driver is backing off,
    // which the free-running clock ends at the next step: bounded.
    for (std::size_t k = 0; k < 2 * log.size() + 16 && !log.diverged() && !log.at_end(); ++k) {
      device.step(kDeviceStepTimeoutNs);
    }
    const std::string stream = "stream '" + std::string(device.name()) + "'";
    if (log.divergence_kind() == hal::replay::DivergenceKind::kMismatch) {
      result.diverged = true;
      result.error = "replay diverged from the recording in " + stream + ": " + log.divergence();
    } else if (log.diverged()) {
      result.ended_early = true;
      result.note = "the recording of " + stream + " ends early: " + log.divergence();
    }
  }
  if (progress) progress(prog);
  result.published = sink.published;
  result.compared = sink.compared;
  result.identical = sink.identical;
  result.first_mismatch = sink.first_mismatch;
  result.recorded_not_reproduced = sink.not_reproduced();
  pipeline->core().snapshot().load(result.final);
  // Device health as of now, the camera's replayed frames included.
  if (pipeline->hardware() != nullptr) pipeline->hardware()->fill_snapshot(result.final);
  if (!sink.error.empty()) {
    result.error = "writing the output log: " + sink.error;
    return result;
  }
  result.ok = !result.diverged;
  return result;
}

}  // namespace rtfuse
