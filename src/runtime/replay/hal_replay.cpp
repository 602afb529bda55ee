#include "runtime/replay/hal_replay.hpp"

#include <cstdio>
#include <memory>

#include "runtime/devices/device_registry.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "runtime/replay/compare_sink.hpp"
#include "runtime/replay/replay_buses.hpp"

namespace rtfuse {
namespace {

std::string hex64(std::int64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

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

// The configuration as the live run had it: the files its devices read
// (the camera's calibration) from the recording, not from this machine,
// where they may differ or be missing.
RuntimeConfig recorded_config(const HalRecording& rec, const RuntimeConfig& given) {
  RuntimeConfig cfg = given;
  for (const transport::RecordedFile& f : rec.info.files) {
    for (int i = 0; i < device_type_count(); ++i) {
      if (device_type(i).enabled(cfg)) device_type(i).restore_file(f, cfg);
    }
  }
  return cfg;
}

// A HAL recording replays driver inputs only: a sensor that took LCM
// messages live would be starved here, and the outputs could not match.
std::string lcm_inputs_used(const HalRecording& rec, const RuntimeConfig& cfg) {
  for (int i = 0; i < cfg.num_sensors; ++i) {
    if (cfg.sensors[static_cast<std::size_t>(i)].source != kLcmSource) continue;
    for (const transport::LoopTick& t : rec.ticks) {
      if (static_cast<int>(t.consumed.size()) > i && t.consumed[static_cast<std::size_t>(i)] > 0) {
        return "sensor '" + std::string(cfg.sensors[static_cast<std::size_t>(i)].name.view()) +
               "' took LCM messages during the recording; a HAL recording replays driver inputs only";
      }
    }
  }
  return "";
}

// One recording through one tick pipeline, tick by tick.
class HalReplay {
 public:
  HalReplay(const HalRecording& rec, HalReplayResult& result) : rec_(rec), result_(result) {}

  // Binds the recorded buses, makes the pipeline and starts its devices at
  // the recording's start time. False with result_.error (or a divergence).
  bool set_up(const RuntimeConfig& cfg, transport::EventLogWriter* out);
  // Every recorded tick, each after the thread devices caught up with it.
  void run_ticks(const std::function<void(const HalReplayProgress&)>& progress);
  // What a camera did after the loop's last intake.
  void finish_video();
  // What the last tick made due, as the live runtime finishes after its
  // threads stopped.
  void finish_workers();
  void collect();

 private:
  // Steps each thread device on its stream until it pushed the samples the
  // live loop had taken by tick t. False when the replay stops there.
  bool catch_up(const transport::LoopTick& t);
  // Hands each device the recorded inputs the live loop had taken by tick t.
  void deliver_inputs(const transport::LoopTick& t);
  // Lets the workers (the mapper, the navigator) do what is due: after
  // every tick and every camera step. What they do does not depend on how
  // often they are stepped, only on what was due.
  void step_workers();
  // A divergence or the end of a stream stops the replay: true then.
  bool stopped_by_a_stream();
  bool stopped_by_video(const hal::replay::ReplayVideoLog* v, const char* device);

  const HalRecording& rec_;
  HalReplayResult& result_;
  std::unique_ptr<ReplayBuses> buses_;
  std::unique_ptr<CompareSink> sink_;
  std::unique_ptr<TickPipeline> pipeline_;
  std::unique_ptr<ReplayOutput> output_;
  TimeNs t0_ = 0;
  LoopStats loop_;
  std::vector<std::size_t> input_cursor_;  // per device input: the next of rec_.inputs to look at
  std::vector<std::int64_t> inputs_given_;
};

bool HalReplay::set_up(const RuntimeConfig& given, transport::EventLogWriter* out) {
  const RuntimeConfig cfg = recorded_config(rec_, given);
  result_.error = lcm_inputs_used(rec_, cfg);
  if (!result_.error.empty()) return false;
  buses_ = ReplayBuses::bind(rec_, cfg, &result_.error);
  if (!buses_) return false;
  std::string err;
  sink_ = std::make_unique<CompareSink>(rec_, cfg, out);
  PipelineOptions options;
  options.sink = sink_.get();
  pipeline_ = TickPipeline::create(cfg, buses_->buses(), options, &err);
  if (!pipeline_) {
    result_.error = err;
    return false;
  }
  output_ = std::make_unique<ReplayOutput>(pipeline_->publisher(), pipeline_->sink(), rec_);
  t0_ = rec_.info.start_ns != 0 ? rec_.info.start_ns : (rec_.ticks.empty() ? 0 : rec_.ticks.front().time_ns);
  if (!pipeline_->start(t0_, &err)) {
    if (!stopped_by_a_stream()) result_.error = "starting the devices from the recording failed: " + err;
    return false;
  }
  loop_.rate_hz = cfg.rate_hz;
  loop_.period_ns = static_cast<std::int64_t>(1e9 / cfg.rate_hz);
  return true;
}

bool HalReplay::stopped_by_a_stream() {
  for (const auto& s : rec_.streams) {
    if (!s->diverged()) continue;
    // A different call is a divergence; running out of recorded calls (a
    // truncated recording, a ring that overflowed) ends the replay early.
    if (s->divergence_kind() == hal::replay::DivergenceKind::kMismatch) {
      result_.diverged = true;
      result_.error = "replay diverged from the recording in stream '" + s->name() + "': " + s->divergence();
    } else {
      result_.ended_early = true;
      result_.note = "the recording of stream '" + s->name() + "' ends before its last tick: " + s->divergence();
    }
    return true;
  }
  return false;
}

bool HalReplay::stopped_by_video(const hal::replay::ReplayVideoLog* v, const char* device) {
  if (v == nullptr || v->divergence_kind() != hal::replay::DivergenceKind::kMismatch) return false;
  result_.diverged = true;
  result_.error = "replay diverged from the recording in stream '" + std::string(device) + "': " + v->divergence();
  return true;
}

bool HalReplay::catch_up(const transport::LoopTick& t) {
  for (int d = 0; d < pipeline_->thread_device_count(); ++d) {
    Device& device = pipeline_->thread_device(d);
    const char* name = pipeline_->thread_device_name(d);
    const ReplayedDevice& r = buses_->device(name);
    const int sensor = device.sensor();
    if (r.stream == nullptr || sensor < 0 || static_cast<int>(t.consumed.size()) <= sensor) continue;
    const std::int64_t target = t.consumed[static_cast<std::size_t>(sensor)];
    auto more = [&] {
      return r.video != nullptr ? !r.video->diverged() && !r.video->at_end() : !r.stream->diverged() && !r.stream->at_end();
    };
    // The device's thread ran ahead of the loop: replay its calls until the
    // loop has what it took live. A stream that ends or diverges first
    // cannot give more.
    if (r.free_clock != nullptr && device.samples() < target) r.free_clock->sleep_until(t.time_ns);
    while (device.samples() < target && more()) {
      device.step(kDeviceStepTimeoutNs);
      // A camera's pairs that gave the loop no sample (skipped, or while
      // its odometry restarted) come here in one burst at the next tick
      // that took one. Live, the mapper's thread mapped each keyframe
      // among them once the loop was past it, before the next arrived;
      // without a step between them its queue of two would overflow here
      // and drop a keyframe the live mapper kept.
      if (r.video != nullptr) step_workers();
    }
    if (stopped_by_video(r.video, name)) return false;
    // Ticking on without the samples the live loop had would publish
    // something it never published: the recording ends here.
    if (device.samples() < target && !r.stream->diverged()) {
      result_.ended_early = true;
      result_.note = "the recording of stream '" + r.stream->name() + "' ends before tick " + std::to_string(t.seq) +
                     ": it holds " + std::to_string(device.samples()) + " of the " + std::to_string(target) + " " +
                     name + " samples the loop had taken by then";
      return false;
    }
  }
  return true;
}

void HalReplay::deliver_inputs(const transport::LoopTick& t) {
  Hardware* hw = pipeline_->hardware();
  if (hw == nullptr || hw->input_count() == 0) return;
  if (input_cursor_.empty()) {
    input_cursor_.assign(static_cast<std::size_t>(hw->input_count()), 0);
    inputs_given_.assign(static_cast<std::size_t>(hw->input_count()), 0);
  }
  const std::size_t first = static_cast<std::size_t>(pipeline_->config().num_sensors);
  for (int i = 0; i < hw->input_count(); ++i) {
    const std::size_t k = first + static_cast<std::size_t>(i);
    if (t.consumed.size() <= k) continue;
    const std::string& channel = hw->input_channel(i);
    std::size_t& at = input_cursor_[static_cast<std::size_t>(i)];
    std::int64_t& given = inputs_given_[static_cast<std::size_t>(i)];
    while (given < t.consumed[k] && at < rec_.inputs.size()) {
      const RecordedOutput& in = rec_.inputs[at++];
      if (in.channel != channel) continue;
      pipeline_->deliver_input(i, in.bytes.data(), static_cast<int>(in.bytes.size()), utime_to_ns(in.utime));
      ++given;
    }
  }
}

void HalReplay::run_ticks(const std::function<void(const HalReplayProgress&)>& progress) {
  HalReplayProgress prog;
  prog.total_ticks = static_cast<std::int64_t>(rec_.ticks.size());
  for (const transport::LoopTick& t : rec_.ticks) {
    if (!catch_up(t) || stopped_by_a_stream()) break;
    deliver_inputs(t);
    ++loop_.ticks;
    output_->expect(t.published);
    pipeline_->step(t.time_ns, loop_, *output_);
    if (stopped_by_a_stream()) break;
    // Workers (the mapper) do what this tick made due, as their live thread
    // did at some later moment: what they do does not depend on when.
    step_workers();
    ++result_.ticks;
    ++prog.ticks;
    if (progress && prog.ticks % 10000 == 0) progress(prog);
  }
  if (progress) progress(prog);
}

void HalReplay::finish_video() {
  // What a camera did after the last sample the loop took (all of it for a
  // camera without a consumer feeding a sensor) changes no tick: its
  // recorded calls are replayed after the ticks, through the same driver,
  // in their recorded order, so its counters and digest end where the live
  // camera's did.
  for (int d = 0; d < pipeline_->thread_device_count() && !result_.diverged && !result_.ended_early; ++d) {
    Device& device = pipeline_->thread_device(d);
    const char* name = pipeline_->thread_device_name(d);
    const ReplayedDevice& r = buses_->device(name);
    if (r.video == nullptr) continue;
    hal::replay::ReplayVideoLog& log = *r.video;
    if (r.free_clock != nullptr) r.free_clock->sleep_until(t0_);
    // Each step makes at least one call unless the driver is backing off,
    // which the free-running clock ends at the next step: bounded.
    for (std::size_t k = 0; k < 2 * log.size() + 16 && !log.diverged() && !log.at_end(); ++k) {
      device.step(kDeviceStepTimeoutNs);
      step_workers();  // as in catch_up: the mapper takes each pair as its thread did
    }
    const std::string stream = "stream '" + std::string(name) + "'";
    if (log.divergence_kind() == hal::replay::DivergenceKind::kMismatch) {
      result_.diverged = true;
      result_.error = "replay diverged from the recording in " + stream + ": " + log.divergence();
    } else if (log.diverged()) {
      result_.ended_early = true;
      result_.note = "the recording of " + stream + " ends early: " + log.divergence();
    }
  }
}

void HalReplay::step_workers() {
  if (Hardware* hw = pipeline_->hardware()) hw->step_workers();
}

void HalReplay::finish_workers() {
  if (Hardware* hw = pipeline_->hardware()) hw->finish_workers();
}

void HalReplay::collect() {
  result_.published = sink_->published;
  result_.compared = sink_->compared;
  result_.identical = sink_->identical;
  result_.first_mismatch = sink_->first_mismatch;
  result_.recorded_not_reproduced = sink_->not_reproduced();
  pipeline_->core().snapshot().load(result_.final);
  // Device health as of now, the camera's replayed frames included.
  if (pipeline_->hardware() != nullptr) pipeline_->hardware()->fill_snapshot(result_.final);
  if (!sink_->error.empty()) {
    result_.error = "writing the output log: " + sink_->error;
    return;
  }
  result_.ok = !result_.diverged;
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

HalReplayResult replay_hal_recording(const HalRecording& rec, const RuntimeConfig& cfg,
                                     transport::EventLogWriter* out,
                                     const std::function<void(const HalReplayProgress&)>& progress) {
  HalReplayResult result;
  HalReplay replay(rec, result);
  if (!replay.set_up(cfg, out)) return result;
  replay.run_ticks(progress);
  replay.finish_video();
  replay.finish_workers();
  replay.collect();
  return result;
}

}  // namespace rtfuse
