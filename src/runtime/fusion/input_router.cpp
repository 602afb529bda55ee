#include "runtime/fusion/input_router.hpp"

#include <cmath>
#include <cstring>

namespace rtfuse {

InputRouter::InputRouter(const RuntimeConfig& cfg, const geometry::FrameTree& frames)
    : cfg_(cfg), num_sensors_(cfg.num_sensors), decoder_(frames) {
  for (int i = 0; i < num_sensors_; ++i) {
    const SensorConfig& sc = cfg.sensors[i];
    if (sc.max_rate_hz > 0.0) {
      limits_[i].interval = static_cast<TimeNs>(std::llround(1e9 / sc.max_rate_hz));
      limits_[i].tolerance = (2 * sc.params.queue_size - 1) * limits_[i].interval;
    }
    // Twice the robot_localization queue: one tick drains queue_size, the
    // rest absorbs a producer burst while the loop is mid-tick.
    rings_[i] = std::make_unique<SpscRing<est::SensorSample>>(
        static_cast<std::size_t>(2 * cfg.sensors[i].params.queue_size));
  }
}

bool InputRouter::on_message(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept {
  const bool oversize = size > cfg_.lcm_max_message_bytes;
  for (int i = 0; i < num_sensors_; ++i) {
    if (cfg_.sensors[i].source != kLcmSource) continue;  // a driver feeds it
    if (std::strcmp(cfg_.sensors[i].channel.c_str(), channel) != 0) continue;
    InputCounters& c = counters_[i];
    c.received.fetch_add(1, std::memory_order_relaxed);
    // Both checks before decoding: a flood costs the LCM thread a compare
    // per message, not a decode.
    if (oversize) {
      c.oversize.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    if (!limits_[i].admit(now)) {
      c.rate_limited.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    if (decoder_.decode(cfg_.sensors[i].params.kind, data, size, &scratch_) != transport::DecodeResult::kOk) {
      c.decode_errors.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    // A stamp ahead of the arrival by more than clock skew and jitter can
    // explain would move the filter's time forward and make every honest
    // sensor stale: a broken or hostile sender must not get that far.
    if (scratch_.stamp - now > cfg_.lcm_max_stamp_ahead_ns) {
      c.ahead.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    scratch_.sensor = static_cast<std::uint8_t>(i);
    if (!rings_[i]->try_push(scratch_)) c.overflow.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  if (std::strcmp(cfg_.publish.set_pose_channel.c_str(), channel) == 0) {
    if (!cfg_.publish.accept_set_pose) {
      set_pose_ignored_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    if (oversize) {
      set_pose_errors_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    SetPoseCommand cmd;
    if (decoder_.decode_set_pose(data, size, &cmd.pose, &cmd.stamp, &cmd.frame) != transport::DecodeResult::kOk) {
      set_pose_errors_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    if (cmd.stamp - now > cfg_.lcm_max_stamp_ahead_ns) {
      set_pose_errors_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    // A burst beyond the ring before the loop's next tick: counted, not lost silently.
    if (!set_pose_ring_.try_push(cmd)) set_pose_errors_.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  unknown_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

}  // namespace rtfuse
