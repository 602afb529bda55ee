#pragma once
// Producer side of the loop: raw LCM bytes of a configured channel are
// decoded (off the real-time path) and handed over through SPSC rings. Used by
// the LCM-in thread live and by the replay in lockstep: the same code path.
#include <atomic>
#include <cstdint>
#include <memory>

#include "core/spsc_ring.hpp"
#include "estimation/sensor_sample.hpp"
#include "runtime/config/config.hpp"
#include "transport/sample_decoder.hpp"

namespace rtfuse {

struct SetPoseCommand {
  TimeNs stamp = 0;
  std::int16_t frame = -1;
  est::PoseSample pose;
};

// Counters the producer owns; the loop only reads them (relaxed).
struct InputCounters {
  std::atomic<std::int64_t> received{0};
  std::atomic<std::int64_t> decode_errors{0};
  std::atomic<std::int64_t> overflow{0};
  std::atomic<std::int64_t> oversize{0};      // above [lcm] max_message_bytes, not decoded
  std::atomic<std::int64_t> rate_limited{0};  // beyond the sensor's max_rate, not decoded
  std::atomic<std::int64_t> ahead{0};         // stamped further ahead of its arrival than [lcm] max_stamp_ahead
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

class InputRouter {
 public:
  InputRouter(const RuntimeConfig& cfg, const geometry::FrameTree& frames);

  // One producer thread only. Returns false for channels that are not inputs.
  // `now` is when the message arrived (CLOCK_MONOTONIC live, the log's time
  // in a replay): the rate limits count in it, so replaying a log drops the
  // same messages every time, and what the live run dropped as far as the
  // logger's receive times match the daemon's.
  bool on_message(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept;

  // Consumer side (the loop).
  SpscRing<est::SensorSample>& ring(int sensor) { return *rings_[sensor]; }
  SpscRing<SetPoseCommand>& set_pose_ring() { return set_pose_ring_; }
  const InputCounters& counters(int sensor) const { return counters_[sensor]; }
  // For a driver that feeds a sensor's ring itself (its only producer):
  // counts it as received, or as overflow when the ring is full.
  bool push_from_driver(int sensor, const est::SensorSample& s) noexcept {
    InputCounters& c = counters_[sensor];
    c.received.fetch_add(1, std::memory_order_relaxed);
    if (rings_[sensor]->try_push(s)) return true;
    c.overflow.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::int64_t unknown_channel_messages() const { return unknown_.load(std::memory_order_relaxed); }
  // Malformed or oversize set_pose messages, and those the ring had no room for.
  std::int64_t set_pose_decode_errors() const { return set_pose_errors_.load(std::memory_order_relaxed); }
  // set_pose messages dropped because [publish] accept_set_pose is false.
  std::int64_t set_pose_ignored() const { return set_pose_ignored_.load(std::memory_order_relaxed); }
  int num_sensors() const { return num_sensors_; }

 private:
  const RuntimeConfig& cfg_;
  int num_sensors_;
  transport::SampleDecoder decoder_;
  std::unique_ptr<SpscRing<est::SensorSample>> rings_[kMaxSensors];
  SpscRing<SetPoseCommand> set_pose_ring_{4};
  InputCounters counters_[kMaxSensors];
  std::atomic<std::int64_t> unknown_{0};
  std::atomic<std::int64_t> set_pose_errors_{0};
  std::atomic<std::int64_t> set_pose_ignored_{0};
  // Rate limit per sensor, the generic cell rate algorithm: a message is
  // taken when its theoretical arrival time is at most `tolerance` ahead of
  // now. Integer nanoseconds: the same arrival times give the same decisions
  // on every machine.
  // An interval of 0 admits everything (a config built without the loader).
  struct RateLimit {
    TimeNs interval = 0;   // 1 / max_rate
    TimeNs tolerance = 0;  // (burst - 1) intervals
    TimeNs tat = 0;        // theoretical arrival time of the next message
    bool started = false;
    bool admit(TimeNs now) noexcept {
      if (!started) {
        started = true;
        tat = now;
      }
      const TimeNs next = tat > now ? tat : now;
      if (next - now > tolerance) return false;
      tat = next + interval;
      return true;
    }
  };
  RateLimit limits_[kMaxSensors];
  est::SensorSample scratch_;
};

}  // namespace rtfuse
