#include "runtime/runtime.hpp"

#include <algorithm>
#include <atomic>

#include "runtime/lcm_sink.hpp"
#include "runtime/loop_timer.hpp"
#include "runtime/realtime.hpp"

namespace rtfuse {

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, std::string* error) {
  return create(cfg, HalBuses{}, error);
}

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, const HalBuses& buses, std::string* error) {
  return create(cfg, buses, std::string(), std::string(), error);
}

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, const HalBuses& buses_in,
                                         const std::string& record_path, const std::string& config_text,
                                         std::string* error) {
  std::unique_ptr<Runtime> rt(new Runtime());
  rt->core_ = FusionCore::create(cfg, error);
  if (!rt->core_) return nullptr;
  HalBuses buses = buses_in;
  if (!record_path.empty()) {
    rt->tap_ = RecordingTap::create(record_path, rt->core_->config(), config_text, buses, rt->clock_,
                                    monotonic_now_ns(), error);
    if (!rt->tap_) return nullptr;
    buses = rt->tap_->buses();
  }
  if (cfg.hardware.can.enabled || cfg.hardware.mpu.enabled) {
    rt->hardware_ = Hardware::create(buses, *rt->core_, error);
    if (!rt->hardware_) return nullptr;
    rt->core_->set_devices(rt->hardware_.get());
  }
  rt->publisher_ = std::make_unique<Publisher>(rt->core_->config());
  rt->lcm_ = transport::LcmNode::create(cfg.lcm_url, error);
  if (!rt->lcm_) return nullptr;
  // The publisher thread's sinks, built here: its loop allocates nothing.
  rt->lcm_sink_ = std::make_unique<LcmSink>(*rt->lcm_);
  if (rt->tap_) rt->recording_sink_ = std::make_unique<runtime::RecordingSink>(*rt->lcm_sink_, rt->tap_->recorder());
  const RuntimeConfig& c = rt->core_->config();
  for (int i = 0; i < c.num_sensors; ++i) {
    if (c.sensors[i].source != SensorSource::kLcm) continue;
    if (!rt->lcm_->subscribe(c.sensors[i].channel.c_str(), &Runtime::on_lcm, rt->core_.get())) {
      *error = "cannot subscribe to channel '" + std::string(c.sensors[i].channel.view()) + "'";
      return nullptr;
    }
  }
  if (!rt->lcm_->subscribe(c.publish.set_pose_channel.c_str(), &Runtime::on_lcm, rt->core_.get())) {
    *error = "cannot subscribe to the set_pose channel";
    return nullptr;
  }
  return rt;
}

Runtime::~Runtime() { stop(); }

void Runtime::on_lcm(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user) {
  static_cast<FusionCore*>(user)->input().on_message(channel, data, size);
}

bool Runtime::start(std::string* error, std::string* warnings) {
  const RealtimeConfig& rtc = core_->config().realtime;
  const RealtimeOutcome mem = apply_memory_lock(rtc);
  if (!mem.ok) {
    if (rtc.require) {
      *error = mem.warnings + "realtime.require = true: refusing to run without it";
      return false;
    }
    *warnings += mem.warnings;
  }
  // Devices answer before anything runs: a missing chip or a bus that
  // refuses the NMT start stops here with the device named.
  if (tap_ && !tap_->recorder().start(error)) return false;
  // A recording holds the start time it was created with, so its replay
  // starts the devices at the same time (boot-up and NMT timing depend on it).
  const TimeNs start = tap_ ? tap_->recorder().info().start_ns : monotonic_now_ns();
  if (hardware_ && !hardware_->start(start, error)) return false;
  running_.store(true);
  // The loop thread applies its own scheduling; start() waits for its verdict
  // so a required-but-refused setting stops the process before it runs.
  loop_ = std::thread(&Runtime::loop_thread, this);
  while (!steady_.load(std::memory_order_acquire) && !rt_failed_.load(std::memory_order_acquire)) {
    std::this_thread::yield();
  }
  if (rt_failed_.load()) {
    if (rtc.require) {
      running_.store(false);
      loop_.join();
      *error = rt_warnings_ + "realtime.require = true: refusing to run without it";
      return false;
    }
    *warnings += rt_warnings_;
  }
  pub_ = std::thread(&Runtime::publisher_thread, this);
  lcmin_ = std::thread(&Runtime::input_thread, this);
  if (hardware_ && hardware_->has_imu()) imu_ = std::thread(&Runtime::imu_thread, this);
  return true;
}

bool Runtime::stop(std::string* error) {
  running_.store(false);
  if (loop_.joinable()) loop_.join();
  if (pub_.joinable()) pub_.join();
  if (lcmin_.joinable()) lcmin_.join();
  if (imu_.joinable()) imu_.join();
  // Producers are gone: the recorder drains what is left and closes.
  return tap_ ? tap_->recorder().stop(error) : true;
}

Snapshot Runtime::latest() const {
  Snapshot s;
  core_->snapshot().load(s);
  return s;
}

void Runtime::loop_thread() {
  name_this_thread("rtfuse-loop");
  const RealtimeOutcome r = apply_thread_realtime(core_->config().realtime);
  if (!r.ok) {
    rt_warnings_ = r.warnings;
    rt_failed_.store(true, std::memory_order_release);
    if (core_->config().realtime.require) return;
  }
  LoopTimer timer(core_->config().rate_hz, monotonic_now_ns());
  // One tick before declaring steady state, so first-touch effects are over.
  loop_tick(monotonic_now_ns(), timer.stats());
  steady_.store(true, std::memory_order_release);
  while (running_.load(std::memory_order_relaxed)) {
    sleep_until(timer.deadline());
    const TimeNs woke = monotonic_now_ns();
    loop_tick(woke, timer.stats());
    timer.record(woke, monotonic_now_ns());
  }
}

void Runtime::loop_tick(TimeNs now, const LoopStats& stats) noexcept {
  core_->tick(now, stats);
  const Snapshot& snap = core_->last_snapshot();
  std::uint32_t queued = publisher_->schedule(snap, now);
  if (queued != 0) {
    job_.snapshot = snap;
    job_.due = queued;
    if (!publish_jobs_.try_push(job_)) {
      publish_drops_.fetch_add(1, std::memory_order_relaxed);
      queued = 0;
    }
  }
  // What was queued, not what was due: a replay must publish what went out.
  if (tap_) tap_->recorder().record_tick(now, snap.seq, core_->consumed(), core_->config().num_sensors, queued);
}

void Runtime::publisher_thread() {
  name_this_thread("rtfuse-pub");
  MessageSink& sink = recording_sink_ ? static_cast<MessageSink&>(*recording_sink_) : *lcm_sink_;
  // The loop queues what is due; a 1 ms wake-up keeps outputs within a
  // millisecond of their tick at any rate.
  const TimeNs period = 1'000'000;
  TimeNs next = monotonic_now_ns();
  for (;;) {
    const bool running = running_.load(std::memory_order_acquire);
    while (const PublishJob* job = publish_jobs_.peek()) {
      publisher_->publish(job->snapshot, job->due, monotonic_now_ns(), sink);
      publish_jobs_.pop();
    }
    if (!running) break;  // the loop has stopped: everything it queued is out
    next += period;
    sleep_until(next);
  }
}

void Runtime::input_thread() {
  name_this_thread("rtfuse-lcmin");
  while (running_.load(std::memory_order_relaxed)) {
    // Bounded wait so a stop request is seen within 50 ms.
    lcm_->handle_timeout(50);
  }
}

void Runtime::imu_thread() {
  name_this_thread("rtfuse-imu");
  while (running_.load(std::memory_order_relaxed)) {
    // A 50 ms edge wait bounds how long a stop request waits; a missing edge
    // is the driver's to count, not a reason to leave.
    hardware_->imu_step(50'000'000);
  }
}

}  // namespace rtfuse
