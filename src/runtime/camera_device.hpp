#pragma once
// The stereo camera as a thread device: each step dequeues one frame,
// rectifies it into the frame pool (consumers take pairs by handle, never by
// copy) and publishes its health through a seqlock the loop reads. It feeds
// no sensor yet: the visual odometry that will turn pairs into motion reads
// the pool.
#include <atomic>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "core/seqlock.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "runtime/device_layout.hpp"
#include "runtime/fusion_core.hpp"
#include "runtime/hal_buses.hpp"
#include "runtime/thread_device.hpp"

namespace rtfuse {

// The driver's config from [camera]: the factory calibration is loaded here
// (start-up), with the file, line and key of anything wrong in it.
bool camera_driver_config(const CameraSection& c, drivers::StereoCameraConfig* out, std::string* error);

class CameraDevice final : public ThreadDevice {
 public:
  // The configuration is the core's; buses.video and buses.clock are required.
  static std::unique_ptr<CameraDevice> create(const CameraBuses& buses, FusionCore& core, int device_slot,
                                              std::string* error);

  const char* name() const noexcept override { return "camera"; }
  void step(TimeNs timeout_ns) noexcept override;
  int sensor() const noexcept override { return -1; }
  std::int64_t samples() const noexcept override { return frames_.load(std::memory_order_acquire); }
  void fill_snapshot(Snapshot& s) noexcept override;

  // Rectified pairs for consumers (visual odometry, the preview).
  FramePool& pool() { return *pool_; }
  const drivers::StereoRectification& rectified() const { return camera_->rectified(); }
  const drivers::StereoCameraStats& stats() const { return camera_->stats(); }  // camera thread only

 private:
  CameraDevice(int device_slot) : slot_(device_slot) {}

  // What the camera thread shares with the loop.
  struct Health {
    drivers::StereoCameraStats stats;
    drivers::StereoStepOutcome last = drivers::StereoStepOutcome::kTimeout;
  };

  int slot_ = -1;
  std::unique_ptr<FramePool> pool_;
  std::unique_ptr<drivers::StereoCamera> camera_;
  drivers::StereoFrameResult result_;
  Health scratch_;
  SeqLock<Health> health_;
  std::atomic<std::int64_t> frames_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
