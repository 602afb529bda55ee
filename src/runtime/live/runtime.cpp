#include "runtime/live/runtime.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>

#include "runtime/live/lcm_sink.hpp"
#include "runtime/live/loop_timer.hpp"
#include "runtime/live/realtime.hpp"

namespace rtfuse {

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, std::string* error) {
  return create(cfg, HalBuses{}, error);
}

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, const HalBuses& buses, std::string* error) {
  return create(cfg, buses, std::string(), std::string(), error);
}

std::unique_ptr<Runtime> Runtime::create(const RuntimeConfig& cfg, const HalBuses& buses,
                                         const std::string& record_path, const std::string& config_text,
                                         std::string* error) {
  std::unique_ptr<Runtime> rt(new Runtime());
  rt->lcm_ = transport::LcmNode::create(cfg.lcm_url, error);
  if (!rt->lcm_) return nullptr;
  // The publisher thread's sink, built here: its loop allocates nothing.
  rt->lcm_sink_ = std::make_unique<LcmSink>(*rt->lcm_);
  PipelineOptions options;
  options.record_path = record_path;
  options.config_text = config_text;
  options.record_clock = &rt->clock_;
  options.start_ns = monotonic_now_ns();
  options.sink = rt->lcm_sink_.get();
  rt->pipeline_ = TickPipeline::create(cfg, buses, options, error);
  if (!rt->pipeline_) return nullptr;
  FusionCore& core = rt->pipeline_->core();
  const RuntimeConfig& c = core.config();
  for (int i = 0; i < c.num_sensors; ++i) {
    if (c.sensors[i].source != kLcmSource) continue;
    if (!rt->lcm_->subscribe(c.sensors[i].channel.c_str(), &Runtime::on_lcm, &core)) {
      *error = "cannot subscribe to channel '" + std::string(c.sensors[i].channel.view()) + "'";
      return nullptr;
    }
  }
  if (!rt->lcm_->subscribe(c.publish.set_pose_channel.c_str(), &Runtime::on_lcm, &core)) {
    *error = "cannot subscribe to the set_pose channel";
    return nullptr;
  }
  if (Hardware* hw = rt->pipeline_->hardware()) {
    for (int i = 0; i < hw->input_count(); ++i) {
      if (!rt->lcm_->subscribe(hw->input_channel(i).c_str(), &Runtime::on_device_input, rt->pipeline_.get())) {
        *error = "cannot subscribe to channel '" + hw->input_channel(i) + "'";
        return nullptr;
      }
    }
  }
  return rt;
}

void Runtime::on_device_input(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user) {
  TickPipeline* p = static_cast<TickPipeline*>(user);
  p->deliver_input(p->hardware()->find_input(channel), data, size, monotonic_now_ns());
}

Runtime::~Runtime() { stop(); }

void Runtime::on_lcm(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user) {
  static_cast<FusionCore*>(user)->input().on_message(channel, data, size, monotonic_now_ns());
}

bool Runtime::start(std::string* error, std::string* warnings) {
  const RealtimeConfig& rtc = config().realtime;
  const RealtimeOutcome mem = apply_memory_lock(rtc);
  if (!mem.ok) {
    if (rtc.require) {
      *error = mem.warnings + "realtime.require = true: refusing to run without it";
      return false;
    }
    *warnings += mem.warnings;
  }
  if (!pipeline_->start(monotonic_now_ns(), error)) return false;
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
  for (int i = 0; i < pipeline_->thread_device_count(); ++i) {
    devices_[i] = std::thread(&Runtime::device_thread, this, i);
  }
  // Workers (the mapper) keep the default policy: below every real-time
  // thread, so a keyframe never delays the loop, capture or the outputs.
  if (Hardware* hw = pipeline_->hardware()) {
    for (int i = 0; i < hw->worker_count(); ++i) workers_[i] = std::thread(&Runtime::worker_thread, this, i);
  }
  // Set from here, so a refusal is known before start() returns; a thread
  // runs its first microseconds under SCHED_OTHER, which is still start-up.
  std::string io_warnings;
  const auto io = [&](std::thread& t, const char* what) {
    if (!t.joinable()) return;
    const RealtimeOutcome r = apply_io_priority(rtc, t.native_handle(), what);
    if (!r.ok && io_warnings.empty()) io_warnings = r.warnings;  // the same refusal for every thread
  };
  io(pub_, "the publisher");
  io(lcmin_, "the LCM input thread");
  for (int i = 0; i < pipeline_->thread_device_count(); ++i) io(devices_[i], pipeline_->thread_device_name(i));
  if (!io_warnings.empty()) {
    if (rtc.require) {
      stop();
      *error = io_warnings + "realtime.require = true: refusing to run without it";
      return false;
    }
    *warnings += io_warnings;
  }
  return true;
}

bool Runtime::stop(std::string* error) {
  running_.store(false);
  if (loop_.joinable()) loop_.join();
  if (pub_.joinable()) pub_.join();
  if (lcmin_.joinable()) lcmin_.join();
  for (std::thread& t : devices_) {
    if (t.joinable()) t.join();
  }
  for (std::thread& t : workers_) {
    if (t.joinable()) t.join();
  }
  // What the last tick made due, as a replay of this run will finish it.
  if (!stopped_.load() && pipeline_ && pipeline_->hardware() != nullptr) pipeline_->hardware()->finish_workers();
  stopped_.store(true);
  // Producers are gone: the recorder drains what is left and closes.
  return pipeline_ ? pipeline_->stop(error) : true;
}

Snapshot Runtime::latest() const {
  Snapshot s;
  pipeline_->core().snapshot().load(s);
  // With every thread joined, the devices' own final health replaces the
  // last tick's view of it (a camera's frames after that tick), as a replay
  // ends with: the two can then be compared.
  if (stopped_.load() && pipeline_->hardware() != nullptr) pipeline_->hardware()->fill_snapshot(s);
  return s;
}

void Runtime::loop_thread() {
  name_this_thread("rtfuse-loop");
  const RealtimeOutcome r = apply_thread_realtime(config().realtime);
  if (!r.ok) {
    rt_warnings_ = r.warnings;
    rt_failed_.store(true, std::memory_order_release);
    if (config().realtime.require) return;
  }
  LoopTimer timer(config().rate_hz, monotonic_now_ns());
  // One tick before declaring steady state, so first-touch effects are over.
  pipeline_->step(monotonic_now_ns(), timer.stats(), queued_output_);
  steady_.store(true, std::memory_order_release);
  while (running_.load(std::memory_order_relaxed)) {
    sleep_until(timer.deadline());
    const TimeNs woke = monotonic_now_ns();
    pipeline_->step(woke, timer.stats(), queued_output_);
    timer.record(woke, monotonic_now_ns());
  }
}

std::uint32_t Runtime::QueuedOutput::deliver(const Snapshot& snap, std::uint32_t due, TimeNs) noexcept {
  if (due == 0) return 0;
  rt_.job_.snapshot = snap;
  rt_.job_.due = due;
  if (rt_.publish_jobs_.try_push(rt_.job_)) return due;
  rt_.publish_drops_.fetch_add(1, std::memory_order_relaxed);
  return 0;
}

void Runtime::publisher_thread() {
  name_this_thread("rtfuse-pub");
  MessageSink& sink = pipeline_->sink();
  Publisher& publisher = pipeline_->publisher();
  // The loop queues what is due; a 1 ms wake-up keeps outputs within a
  // millisecond of their tick at any rate.
  const TimeNs period = 1'000'000;
  TimeNs next = monotonic_now_ns();
  for (;;) {
    const bool running = running_.load(std::memory_order_acquire);
    while (const PublishJob* job = publish_jobs_.peek()) {
      publisher.publish(job->snapshot, job->due, monotonic_now_ns(), sink);
      publish_jobs_.pop();
    }
    if (!running) break;  // the loop has stopped: everything it queued is out
    // The devices' own outputs (a camera's preview) are not recorded: they
    // are for watching, and far larger than a recorded output may be; the
    // recording has the frames themselves.
    if (Hardware* hw = pipeline_->hardware()) hw->publish_due(monotonic_now_ns(), *lcm_sink_);
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

void Runtime::worker_thread(int index) {
  Hardware& hw = *pipeline_->hardware();
  char name[32];
  std::snprintf(name, sizeof name, "rtfuse-%s", hw.worker_name(index));
  name[15] = '\0';  // the kernel's limit
  name_this_thread(name);
  // Below the default too: under load (a busy board, the CPU hog test) the
  // mapper falls behind and drops keyframes, counted, before anything else
  // on the machine waits for it.
  lower_this_thread(10);
  Device& worker = hw.worker(index);
  while (running_.load(std::memory_order_relaxed)) worker.step(kDeviceStepTimeoutNs);
}

void Runtime::device_thread(int index) {
  Device* device = &pipeline_->thread_device(index);
  char name[32];
  std::snprintf(name, sizeof name, "rtfuse-%s", pipeline_->thread_device_name(index));
  name[15] = '\0';  // the kernel's limit
  name_this_thread(name);
  // A step that finds nothing (a missing edge, no frame) is the device's to
  // count, not a reason to leave; the timeout bounds how long a stop waits.
  while (running_.load(std::memory_order_relaxed)) device->step(kDeviceStepTimeoutNs);
}

}  // namespace rtfuse
