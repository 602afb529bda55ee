#include "runtime/pipeline/tick_pipeline.hpp"

#include "runtime/devices/device_registry.hpp"

namespace rtfuse {

TickPipeline::~TickPipeline() = default;

std::unique_ptr<TickPipeline> TickPipeline::create(const RuntimeConfig& cfg, const HalBuses& buses_in,
                                                   const PipelineOptions& options, std::string* error) {
  std::unique_ptr<TickPipeline> p(new TickPipeline());
  // Files a device names (the camera's calibration) are read once, here:
  // the driver and the recording then hold the same bytes.
  RuntimeConfig resolved = cfg;
  bool any_device = false;
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(resolved)) continue;
    any_device = true;
    if (!d.prepare(resolved, error)) return nullptr;
  }
  p->core_ = FusionCore::create(resolved, error);
  if (!p->core_) return nullptr;
  HalBuses buses = buses_in;
  if (!options.record_path.empty()) {
    if (options.record_clock == nullptr) {
      *error = "recording needs a clock to stamp the bus events";
      return nullptr;
    }
    p->tap_ = RecordingTap::create(options.record_path, p->core_->config(), options.config_text, buses,
                                   *options.record_clock, options.start_ns, error);
    if (!p->tap_) return nullptr;
    buses = p->tap_->buses();
  }
  if (any_device) {
    p->hardware_ = Hardware::create(buses, *p->core_, error);
    if (!p->hardware_) return nullptr;
    p->core_->set_devices(p->hardware_.get());
  }
  p->publisher_ = std::make_unique<Publisher>(p->core_->config());
  if (options.sink == nullptr) {
    *error = "the tick pipeline needs a message sink";
    return nullptr;
  }
  p->sink_ = options.sink;
  if (p->tap_) {
    p->recording_sink_ = std::make_unique<runtime::RecordingSink>(*options.sink, p->tap_->recorder());
    p->sink_ = p->recording_sink_.get();
  }
  return p;
}

bool TickPipeline::start(TimeNs now, std::string* error) {
  // Devices answer before anything runs: a missing chip or a bus that
  // refuses the NMT start stops here with the device named.
  if (tap_ && !tap_->recorder().start(error)) return false;
  // A recording holds the start time it was created with, so its replay
  // starts the devices at the same time (boot-up and NMT timing depend on it).
  start_ns_ = tap_ ? tap_->recorder().info().start_ns : now;
  return !hardware_ || hardware_->start(start_ns_, error);
}

void TickPipeline::step(TimeNs now, const LoopStats& stats, OutputStage& out) noexcept {
  core_->tick(now, stats);
  const Snapshot& snap = core_->last_snapshot();
  const std::uint32_t due = publisher_->schedule(snap, now);
  const std::uint32_t handed_on = out.deliver(snap, due, now);
  // What was handed on, not what was due: a replay must publish what went out.
  if (tap_) {
    const int sensors = core_->config().num_sensors;
    int n = 0;
    for (; n < sensors; ++n) consumed_[n] = core_->consumed()[n];
    const int inputs = hardware_ ? hardware_->input_count() : 0;
    for (int i = 0; i < inputs && n < runtime::Recorder::kMaxTickSensors; ++i) consumed_[n++] = hardware_->input_taken(i);
    tap_->recorder().record_tick(now, snap.seq, consumed_, n, handed_on);
  }
}

void TickPipeline::deliver_input(int i, const std::uint8_t* data, int size, TimeNs now) noexcept {
  if (!hardware_ || i < 0 || i >= hardware_->input_count()) return;
  if (tap_) tap_->recorder().record_input(hardware_->input_channel(i).c_str(), data, size, now);
  hardware_->deliver_input(i, data, size, now);
}

bool TickPipeline::stop(std::string* error) { return tap_ ? tap_->recorder().stop(error) : true; }

}  // namespace rtfuse
