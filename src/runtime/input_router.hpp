#pragma once
// Producer side of the loop: raw LCM bytes of a configured channel are
// decoded (off the real-time path) and handed over through SPSC rings. Used by
// the LCM-in thread live and by the replay in lockstep: the same code path.
#include <atomic>
#include <cstdint>
#include <memory>

#include "core/spsc_ring.hpp"
#include "estimation/sensor_sample.hpp"
#include "runtime/config.hpp"
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
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

class InputRouter {
 public:
  InputRouter(const RuntimeConfig& cfg, const geometry::FrameTree& frames);

  // One producer thread only. Returns false for channels that are not inputs.
  bool on_message(const char* channel, const std::uint8_t* data, int size) noexcept;

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
  std::int64_t set_pose_decode_errors() const { return set_pose_errors_.load(std::memory_order_relaxed); }
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
  est::SensorSample scratch_;
};

}  // namespace rtfuse
