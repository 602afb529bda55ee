#pragma once
// The stereo visual odometry as a frame consumer of the camera: on the
// camera's thread, each newest pair (after the first) becomes the left eye's
// twist, pushed into the stereo_vo sensor's ring (visual_odometry.hpp); its
// health crosses to the loop through a SeqLatch.
#include <atomic>
#include <memory>
#include <string>

#include "core/seq_cell.hpp"
#include "runtime/devices/frame_consumer.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/visual_odometry/visual_odometry.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

extern const char* const kVoKeys[14];

class VisualOdometryDevice final : public Device, public FrameConsumer {
 public:
  // On the pairs of `camera`; the configuration is the core's ([vo], the
  // stereo_vo sensor, camera.frame's mount).
  static std::unique_ptr<VisualOdometryDevice> create(FrameSource& camera, FusionCore& core, int slot,
                                                      std::string* error);

  // Device: its slot; its samples are pushed on the camera's thread, so the
  // camera reports them (sensor() and samples() below, as a consumer).
  void fill_snapshot(Snapshot& s) noexcept override;
  FrameConsumer* frame_consumer() noexcept override { return this; }

  // FrameConsumer.
  const char* name() const noexcept override { return "visual odometry"; }
  void on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept override;
  int sensor() const noexcept override { return sensor_; }
  std::int64_t samples() const noexcept override { return samples_.load(std::memory_order_acquire); }

 private:
  VisualOdometryDevice(FusionCore& core, hal::Clock& clock, int slot, int sensor)
      : core_(core), clock_(clock), slot_(slot), sensor_(sensor) {}

  FusionCore& core_;
  hal::Clock& clock_;  // the camera's: its stamps are on it
  int slot_ = -1;
  int sensor_ = -1;
  std::unique_ptr<VisualOdometry> vo_;
  std::uint64_t last_frame_ = 0;  // the last frame id the odometry took
  est::SensorSample sample_;
  SeqLatch<VoStats> health_;
  std::atomic<std::int64_t> samples_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
