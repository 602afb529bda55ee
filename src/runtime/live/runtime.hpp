#pragma once
// The live room around the tick pipeline: the fixed-rate loop thread
// (rtfuse-loop) with its timer and real-time settings, the publisher thread
// (rtfuse-pub), the LCM input thread (rtfuse-lcmin) and one thread per
// thread device (rtfuse-imu, ...); with a recording, the recorder's writer
// (rtfuse-rec). Everything is allocated in create(); the threads allocate
// nothing once running.
//
// Which snapshots are published is decided by the loop on tick time
// (Publisher::schedule) and handed to the publisher thread through a ring,
// so the outputs are a function of the ticks alone: a replay of a recording
// reproduces them byte for byte.
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "core/spsc_ring.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "transport/lcm_node.hpp"

namespace rtfuse {

// A snapshot the loop wants published and which outputs of it (outside
// Runtime: SpscRing needs the type complete).
struct PublishJob {
  Snapshot snapshot;
  std::uint32_t due = 0;
};

class Runtime {
 public:
  // buses: where the configured drivers find their devices (none needed
  // without [can] / [mpu]).
  static std::unique_ptr<Runtime> create(const RuntimeConfig& cfg, std::string* error);
  static std::unique_ptr<Runtime> create(const RuntimeConfig& cfg, const HalBuses& buses, std::string* error);
  // The same, recording every bus event, loop tick and output to
  // record_path (empty: no recording). config_text goes into the recording.
  static std::unique_ptr<Runtime> create(const RuntimeConfig& cfg, const HalBuses& buses,
                                         const std::string& record_path, const std::string& config_text,
                                         std::string* error);
  ~Runtime();

  // Applies the real-time settings and starts the threads. Returns false (and
  // *error) when a required setting is refused or a thread cannot start;
  // refused optional settings are written to *warnings.
  bool start(std::string* error, std::string* warnings);
  // Stops the threads; a recording is drained and closed (false and *error
  // if it could not be written completely).
  bool stop(std::string* error = nullptr);

  // The last tick's snapshot; after stop(), with the devices' final health.
  Snapshot latest() const;
  transport::LcmNode& lcm() { return *lcm_; }
  const RuntimeConfig& config() const { return pipeline_->config(); }
  // Set by the loop after its first steady tick; tests and tools use it to
  // know when start-up allocations are over.
  bool steady() const { return steady_.load(std::memory_order_acquire); }
  // Snapshots the publisher thread could not take in time (ring full).
  std::int64_t publish_drops() const { return publish_drops_.load(std::memory_order_relaxed); }
  const RecordingTap* recording() const { return pipeline_->tap(); }
  // The devices, for what a tool takes from them after stop() (a mapper's
  // map); null without any.
  Hardware* hardware() { return pipeline_->hardware(); }

 private:
  // The loop's outputs go to the publisher thread through a ring; a full
  // ring drops the snapshot (counted) and the tick records that nothing went.
  class QueuedOutput final : public OutputStage {
   public:
    explicit QueuedOutput(Runtime& rt) : rt_(rt) {}
    std::uint32_t deliver(const Snapshot& snap, std::uint32_t due, TimeNs now) noexcept override;

   private:
    Runtime& rt_;
  };

  Runtime() = default;
  void loop_thread();
  void publisher_thread();
  void input_thread();
  void device_thread(int index);
  void worker_thread(int index);
  static void on_lcm(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user);
  // A device's input channel (the navigator's goals): to the device.
  static void on_device_input(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user);

  std::unique_ptr<transport::LcmNode> lcm_;
  std::unique_ptr<MessageSink> lcm_sink_;
  std::unique_ptr<TickPipeline> pipeline_;
  QueuedOutput queued_output_{*this};
  hal::MonotonicClock clock_;
  // Snapshots are large: a few slots cover the publisher thread waking late.
  SpscRing<PublishJob> publish_jobs_{8};
  PublishJob job_;  // the loop's staging copy
  std::atomic<std::int64_t> publish_drops_{0};
  std::atomic<bool> running_{false};
  std::atomic<bool> stopped_{false};  // stop() joined every thread
  std::atomic<bool> steady_{false};
  std::atomic<bool> rt_failed_{false};
  std::string rt_warnings_;
  std::thread loop_, pub_, lcmin_;
  std::thread devices_[kMaxDeviceTypes];
  std::thread workers_[kMaxDeviceTypes];
};

}  // namespace rtfuse
