#pragma once
// One loop tick, the same for the live daemon, the HAL replay and the
// simulated drive: the polled devices, the fusion, the choice of outputs,
// where they go, and the tick's record when recording. The pipeline owns the
// fusion core, the devices, the publisher and the recording tap; the rooms
// around it own what differs: threads, timer and real-time settings (live,
// runtime.hpp), log loading and comparison (hal_replay.hpp), the simulated
// world and its clock (sim/sim_drive.hpp).
#include <cstdint>
#include <memory>
#include <string>

#include "hal/clock.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/devices/hardware.hpp"
#include "runtime/pipeline/publisher.hpp"
#include "runtime/pipeline/recording_tap.hpp"

namespace rtfuse {

struct PipelineOptions {
  std::string record_path;            // empty: no recording
  std::string config_text;            // the TOML, stored in the recording
  hal::Clock* record_clock = nullptr; // stamps the recorded bus events (required when recording)
  TimeNs start_ns = 0;                // when recording: the devices' start time, kept in the recording
  // Where published messages go (the LCM node, a comparison, nowhere); when
  // recording, every message is also recorded on its way there.
  MessageSink* sink = nullptr;
};

// Where a tick's due outputs go: queued to the live publisher thread, or
// published at once (lockstep). Returns the outputs actually handed on,
// which is what a recording stores and a replay publishes.
class OutputStage {
 public:
  virtual ~OutputStage() = default;
  virtual std::uint32_t deliver(const Snapshot& snap, std::uint32_t due, TimeNs now) noexcept = 0;
};

// Publishes what is due on the calling thread (the lockstep drive).
class DirectOutput final : public OutputStage {
 public:
  DirectOutput(Publisher& publisher, MessageSink& sink) : publisher_(publisher), sink_(sink) {}
  std::uint32_t deliver(const Snapshot& snap, std::uint32_t due, TimeNs now) noexcept override {
    publisher_.publish(snap, due, now, sink_);
    return due;
  }

 private:
  Publisher& publisher_;
  MessageSink& sink_;
};

class TickPipeline {
 public:
  static std::unique_ptr<TickPipeline> create(const RuntimeConfig& cfg, const HalBuses& buses,
                                              const PipelineOptions& options, std::string* error);
  ~TickPipeline();

  // Starts the recording's writer, then the devices at `now` (when
  // recording: at the recording's start time): false with *error naming the
  // device.
  bool start(TimeNs now, std::string* error);
  // One tick at loop time `now`. Never allocates, locks or blocks.
  void step(TimeNs now, const LoopStats& stats, OutputStage& out) noexcept;
  // After every producer stopped: drains and closes the recording.
  bool stop(std::string* error);

  FusionCore& core() { return *core_; }
  const FusionCore& core() const { return *core_; }
  const RuntimeConfig& config() const { return core_->config(); }
  Publisher& publisher() { return *publisher_; }
  // The sink outputs are published to (recording them when recording).
  MessageSink& sink() { return *sink_; }
  Hardware* hardware() { return hardware_.get(); }
  int thread_device_count() const { return hardware_ ? hardware_->thread_device_count() : 0; }
  Device& thread_device(int i) { return hardware_->thread_device(i); }
  const char* thread_device_name(int i) const { return hardware_->thread_device_name(i); }
  RecordingTap* tap() { return tap_.get(); }
  const RecordingTap* tap() const { return tap_.get(); }
  // A message on a device's input channel (Hardware::input_channel(i)),
  // recorded first when recording, then handed to the device. One thread
  // only: the LCM thread live, the drive or the replay in lockstep.
  void deliver_input(int i, const std::uint8_t* data, int size, TimeNs now) noexcept;
  // The time the devices were started with.
  TimeNs start_time() const { return start_ns_; }

 private:
  TickPipeline() = default;

  std::unique_ptr<FusionCore> core_;
  std::unique_ptr<RecordingTap> tap_;
  std::unique_ptr<Hardware> hardware_;
  std::unique_ptr<Publisher> publisher_;
  std::unique_ptr<runtime::RecordingSink> recording_sink_;
  MessageSink* sink_ = nullptr;
  TimeNs start_ns_ = 0;
  // A tick's record: the sensors' intake, then the devices' inputs'.
  std::int64_t consumed_[runtime::Recorder::kMaxTickSensors] = {};
};

}  // namespace rtfuse
