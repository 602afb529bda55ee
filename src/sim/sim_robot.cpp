#include "sim/sim_robot.hpp"

#include <limits>

#include "sim/ground_truth.hpp"
#include "transport/encode_buffer.hpp"

namespace rtfuse::sim {

std::unique_ptr<SimRobot> SimRobot::create(const RuntimeConfig& cfg, const std::string& scenario_path,
                                                       hal::Clock& clock, TimeNs t0, std::string* error,
                                                       const std::string_view* scenario_text) {
  std::unique_ptr<SimRobot> r(new SimRobot());
  r->scenario_path_ = scenario_path.empty() ? cfg.hardware.scenario : scenario_path;
  const std::string& path = r->scenario_path_;
  if (path.empty()) {
    *error = "no drive scenario: set [hardware] scenario or give --scenario";
    return nullptr;
  }
  const bool loaded = scenario_text != nullptr
                          ? load_drive_scenario_string(*scenario_text, path, &r->scenario_, error)
                          : load_drive_scenario(path, &r->scenario_, error);
  if (!loaded) return nullptr;
  r->truth_ = std::make_unique<TruthTrajectory>(r->scenario_);
  if (!r->truth_->valid()) {
    *error = path + ": the path cannot be driven within the motion limits";
    return nullptr;
  }
  r->clock_ = &clock;
  r->t0_ = t0;
  if (r->commanded()) {
    // The noise over the whole run: there is no path to end it earlier.
    r->slip_ = std::make_unique<WheelSlipModel>(r->scenario_, r->scenario_.duration_s);
    r->commands_ = std::make_unique<CommandFeed>();
    r->own_truth_ = r->make_truth_reader();
  }
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    // A device on another's frames (the visual odometry) has no buses.
    if (!d.enabled(cfg) || d.required_buses(cfg) == 0) continue;
    const SimCounterpart* c = find_sim_counterpart(d.name());
    if (c == nullptr) {
      *error = cfg.source + ": [" + std::string(d.sections().front()) + "] is configured but the simulated robot has no " +
               d.name();
      return nullptr;
    }
    // Each device reads truth on its own thread: a commanded robot gives it
    // its own integrator, a scripted one the shared, thread-safe trajectory.
    TruthSource* truth = r->truth_.get();
    if (r->commanded()) {
      r->device_truth_[i] = r->make_truth_reader();
      truth = r->device_truth_[i].get();
    }
    const SimDeviceContext ctx{cfg, r->scenario_, path, *truth, clock, t0};
    r->devices_[i] = c->create(ctx, error);
    if (!r->devices_[i]) return nullptr;
  }
  return r;
}

HalBuses SimRobot::buses() {
  HalBuses b;
  for (int i = 0; i < kMaxDeviceTypes; ++i) {
    if (devices_[i]) devices_[i]->provide(b.device[i], *clock_);
  }
  return b;
}

double SimRobot::duration_s() const { return truth_->duration_s(); }

TruthState SimRobot::truth_at(TimeNs t) const noexcept {
  if (own_truth_) return own_truth_->truth_at(ns_to_sec(t - t0_));
  return truth_->truth_at(ns_to_sec(t - t0_));
}

std::unique_ptr<CommandedTruth> SimRobot::make_truth_reader() const {
  if (!commanded()) return nullptr;
  return std::make_unique<CommandedTruth>(scenario_, *slip_, *commands_, t0_);
}

const CommandedTruth* SimRobot::device_truth(std::string_view name) const noexcept {
  const int i = find_device_type(name);
  return i < 0 ? nullptr : device_truth_[i].get();
}

SimRobot::CommandedCounters SimRobot::commanded_counters() const noexcept {
  CommandedCounters c;
  if (!commanded()) return c;
  const auto add = [&c](const CommandedTruth& r) {
    c.late_commands += r.late_commands();
    c.feed_overruns += r.feed_overruns();
    c.history_misses += r.history_misses();
    c.far_queries += r.far_queries();
  };
  for (const auto& r : device_truth_) {
    if (r) add(*r);
  }
  add(*own_truth_);
  c.watchdog_stops = own_truth_->watchdog_stops();
  c.rejected_commands = commands_->rejected_out_of_order();
  c.non_finite_commands = commands_->non_finite();
  return c;
}

GroundTruthEncoder::GroundTruthEncoder() {
  fill_ground_truth(TruthState{}, 0, 0, &msg_);
  buf_.assign(static_cast<std::size_t>(msg_.getEncodedSize() + 64), 0);
  msg_.encode(buf_.data(), 0, static_cast<int>(buf_.size()));
}

const std::uint8_t* GroundTruthEncoder::encode(const TruthState& truth, TimeNs stamp, int* size) noexcept {
  fill_ground_truth(truth, stamp, seq_++, &msg_);
  *size = transport::encode_into(msg_, buf_.data(), static_cast<int>(buf_.size()));
  return buf_.data();
}

TimeNs SimRobot::next_event_time(std::string_view name) noexcept {
  const int i = find_device_type(name);
  if (i < 0 || !devices_[i]) return std::numeric_limits<TimeNs>::max();
  return devices_[i]->next_event_time();
}

}  // namespace rtfuse::sim
