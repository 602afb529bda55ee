#include "runtime/hal_replay.hpp"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <map>
#include <vector>

#include "hal/mock/replay_can_bus.hpp"
#include "hal/mock/replay_clock.hpp"
#include "hal/mock/replay_gpio.hpp"
#include "hal/mock/replay_i2c_bus.hpp"
#include "runtime/fusion_core.hpp"
#include "runtime/hardware.hpp"
#include "runtime/publisher.hpp"
#include "runtime/recording_tap.hpp"

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
  CompareSink(const transport::HalRecording& rec, const RuntimeConfig& cfg, transport::EventLogWriter* out)
      : diagnostics_(cfg.publish.diagnostics_channel.view()), out_(out) {
    const std::string estimate[] = {std::string(cfg.publish.odometry_channel.view()),
                                    std::string(cfg.publish.pose_channel.view()),
                                    std::string(cfg.publish.tf_channel.view()),
                                    std::string(cfg.publish.state_channel.view()),
                                    std::string(cfg.hardware.wheel_odometry.raw_channel.view())};
    for (const transport::RecordedOutput& o : rec.outputs) {
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
    const transport::RecordedOutput& r = *it->second[next++];
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
  std::map<std::string, std::vector<const transport::RecordedOutput*>> recorded_;
  std::map<std::string, std::size_t> next_;
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

HalReplayResult replay_hal_recording(const transport::HalRecording& rec, const RuntimeConfig& cfg,
                                     transport::EventLogWriter* out,
                                     const std::function<void(const HalReplayProgress&)>& progress) {
  HalReplayResult result;
  const int loop = stream_index(rec.info, kLoopStream);
  const int imu = stream_index(rec.info, kImuStream);
  std::vector<std::unique_ptr<hal::CanBus>> cans;
  std::unique_ptr<hal::I2cBus> i2c;
  std::unique_ptr<hal::GpioEdgeSource> drdy;
  std::unique_ptr<hal::Clock> clock;
  HalBuses buses;
  for (std::size_t d = 0; d < rec.info.devices.size(); ++d) {
    const transport::RecordedDevice& dev = rec.info.devices[d];
    hal::mock::ReplayStream& stream = *rec.streams[static_cast<std::size_t>(dev.stream)];
    const auto index = static_cast<std::uint8_t>(d);
    switch (dev.kind) {
      case transport::DeviceKind::kCan:
        if (dev.stream == loop && buses.can == nullptr) {
          cans.push_back(std::make_unique<hal::mock::ReplayCanBus>(stream, index));
          buses.can = cans.back().get();
        }
        break;
      case transport::DeviceKind::kI2c:
        if (dev.stream == imu && !i2c) {
          i2c = std::make_unique<hal::mock::ReplayI2cBus>(stream, index);
          buses.i2c = i2c.get();
        }
        break;
      case transport::DeviceKind::kGpioEdge:
        if (dev.stream == imu && !drdy) {
          drdy = std::make_unique<hal::mock::ReplayEdgeSource>(stream, index);
          buses.drdy = drdy.get();
        }
        break;
      case transport::DeviceKind::kClock:
        if (dev.stream == imu && !clock) {
          clock = std::make_unique<hal::mock::ReplayClock>(stream, index);
          buses.imu_clock = clock.get();
        }
        break;
      case transport::DeviceKind::kGpioOutput: break;
    }
  }
  const HardwareConfig& hw = cfg.hardware;
  if (hw.can.enabled && buses.can == nullptr) {
    result.error = "the configuration has [can] but the recording has no CAN bus of the loop thread";
    return result;
  }
  if (hw.mpu.enabled && (buses.i2c == nullptr || buses.imu_clock == nullptr)) {
    result.error = "the configuration has [mpu] but the recording has no I2C bus and clock of the IMU thread";
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
  std::unique_ptr<FusionCore> core = FusionCore::create(cfg, &err);
  if (!core) {
    result.error = err;
    return result;
  }
  std::unique_ptr<Hardware> hardware;
  if (hw.can.enabled || hw.mpu.enabled) {
    hardware = Hardware::create(buses, *core, &err);
    if (!hardware) {
      result.error = err;
      return result;
    }
    core->set_devices(hardware.get());
  }
  Publisher publisher(core->config());
  CompareSink sink(rec, cfg, out);

  auto diverged = [&]() -> const hal::mock::ReplayStream* {
    for (const auto& s : rec.streams) {
      if (s->diverged()) return s.get();
    }
    return nullptr;
  };
  // A different call is a divergence; running out of recorded calls (a
  // truncated recording, a ring that overflowed) ends the replay early.
  auto stop_diverged = [&](const hal::mock::ReplayStream& s) {
    if (s.divergence_kind() == hal::mock::DivergenceKind::kMismatch) {
      result.diverged = true;
      result.error = "replay diverged from the recording in stream '" + s.name() + "': " + s.divergence();
    } else {
      result.ended_early = true;
      result.note = "the recording of stream '" + s.name() + "' ends before its last tick: " + s.divergence();
    }
  };

  const TimeNs t0 = rec.info.start_ns != 0 ? rec.info.start_ns : (rec.ticks.empty() ? 0 : rec.ticks.front().time_ns);
  if (hardware && !hardware->start(t0, &err)) {
    if (const auto* s = diverged()) {
      stop_diverged(*s);
    } else {
      result.error = "starting the devices from the recording failed: " + err;
    }
    return result;
  }
  const int imu_sensor = hw.mpu_sensor;
  LoopStats loop_stats;
  loop_stats.rate_hz = cfg.rate_hz;
  loop_stats.period_ns = static_cast<std::int64_t>(1e9 / cfg.rate_hz);
  HalReplayProgress prog;
  prog.total_ticks = static_cast<std::int64_t>(rec.ticks.size());
  for (const transport::LoopTick& t : rec.ticks) {
    if (hardware && hardware->has_imu() && imu_sensor >= 0 &&
        static_cast<int>(t.consumed.size()) > imu_sensor) {
      const std::int64_t target = t.consumed[static_cast<std::size_t>(imu_sensor)];
      const hal::mock::ReplayStream& s = *rec.streams[static_cast<std::size_t>(imu)];
      // The IMU thread ran ahead of the loop: replay its calls until the
      // loop has what it took live. A stream that ends or diverges first
      // cannot give more.
      while (hardware->imu_samples() < target && !s.diverged() && !s.at_end()) {
        hardware->imu_step(kImuEdgeTimeoutNs);
      }
      // Ticking on without the samples the live loop had would publish
      // something it never published: the recording ends here.
      if (hardware->imu_samples() < target && !s.diverged()) {
        result.ended_early = true;
        result.note = "the recording of stream '" + s.name() + "' ends before tick " + std::to_string(t.seq) +
                      ": it holds " + std::to_string(hardware->imu_samples()) + " of the " +
                      std::to_string(target) + " IMU samples the loop had taken by then";
        break;
      }
    }
    if (const auto* s = diverged()) {
      stop_diverged(*s);
      break;
    }
    ++loop_stats.ticks;
    core->tick(t.time_ns, loop_stats);
    // A tick whose bus calls ran past the recording (or off it) did not
    // happen as recorded: stop before publishing it.
    if (const auto* s = diverged()) {
      stop_diverged(*s);
      break;
    }
    // The outputs the live loop queued at this tick, no more, no fewer.
    publisher.publish(core->last_snapshot(), t.published, t.time_ns, sink);
    ++result.ticks;
    ++prog.ticks;
    if (progress && prog.ticks % 10000 == 0) progress(prog);
  }
  if (progress) progress(prog);
  result.published = sink.published;
  result.compared = sink.compared;
  result.identical = sink.identical;
  result.first_mismatch = sink.first_mismatch;
  result.recorded_not_reproduced = sink.not_reproduced();
  core->snapshot().load(result.final);
  if (!sink.error.empty()) {
    result.error = "writing the output log: " + sink.error;
    return result;
  }
  result.ok = !result.diverged;
  return result;
}

}  // namespace rtfuse
