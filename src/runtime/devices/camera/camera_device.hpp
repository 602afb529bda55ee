#pragma once
// The stereo camera as a thread device: each step dequeues a frame,
// rectifies it into the frame pool (consumers take pairs by handle, never by
// copy) and, with [vo], runs the visual odometry on the newest pair and
// pushes its twist into the stereo_vo sensor's ring; the health of both
// crosses to the loop through a seqlock.
//
// With the odometry on, a step also takes the frames the device has already
// captured (the driver's catch-up): when the odometry falls behind, the
// frames in between are rectified and published but not processed (counted
// as skipped), so the latency never grows past one frame and the kernel
// never runs out of buffers. A replay makes the same dequeues, so it skips
// the same frames.
#include <atomic>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "core/seqlock.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/devices/thread_device.hpp"
#include "runtime/devices/visual_odometry/visual_odometry.hpp"

namespace rtfuse {

// The driver's config from [camera]: the factory calibration is loaded here
// (start-up), with the file, line and key of anything wrong in it.
bool camera_driver_config(const CameraSection& c, drivers::StereoCameraConfig* out, std::string* error);

class CameraDevice final : public ThreadDevice {
 public:
  // The configuration is the core's; buses.video and buses.clock are required.
  // device_slot, vo_slot: the camera's and the odometry's diagnostics slots.
  static std::unique_ptr<CameraDevice> create(const CameraBuses& buses, FusionCore& core, int device_slot,
                                              int vo_slot, std::string* error);

  const char* name() const noexcept override { return "camera"; }
  void step(TimeNs timeout_ns) noexcept override;
  // With [vo], the odometry's sensor and measurements; else no sensor and
  // the frames published.
  int sensor() const noexcept override { return vo_ ? vo_sensor_ : -1; }
  std::int64_t samples() const noexcept override {
    return vo_ ? vo_samples_.load(std::memory_order_acquire) : frames_.load(std::memory_order_acquire);
  }
  void fill_snapshot(Snapshot& s) noexcept override;

  // Rectified pairs for consumers (visual odometry, the preview).
  FramePool& pool() { return *pool_; }
  const drivers::StereoRectification& rectified() const { return camera_->rectified(); }
  const drivers::StereoCameraStats& stats() const { return camera_->stats(); }  // camera thread only

 private:
  CameraDevice(FusionCore& core, int device_slot, int vo_slot) : core_(core), slot_(device_slot), vo_slot_(vo_slot) {}
  void run_odometry() noexcept;

  // What the camera thread shares with the loop.
  struct Health {
    drivers::StereoCameraStats stats;
    drivers::StereoStepOutcome last = drivers::StereoStepOutcome::kTimeout;
    VoStats vo;
  };

  FusionCore& core_;
  hal::Clock* clock_ = nullptr;
  int slot_ = -1;
  // No frame for this long on the loop's clock and the camera is reported
  // stalled, whatever its thread last said: a device that stops delivering
  // without the driver noticing (a stall shorter than the dequeue timeout
  // each time, a thread that hangs) still shows.
  TimeNs stall_after_ns_ = 0;
  int vo_slot_ = -1;
  int vo_sensor_ = -1;
  std::unique_ptr<VisualOdometry> vo_;
  std::uint64_t vo_frame_ = 0;  // the last frame id the odometry took
  est::SensorSample sample_;
  std::atomic<std::int64_t> vo_samples_{0};
  std::unique_ptr<FramePool> pool_;
  std::unique_ptr<drivers::StereoCamera> camera_;
  drivers::StereoFrameResult result_;
  Health scratch_;
  SeqLock<Health> health_;
  std::atomic<std::int64_t> frames_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
