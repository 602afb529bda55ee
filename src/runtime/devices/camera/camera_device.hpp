#pragma once
// The stereo camera as a thread device: each step dequeues a frame and
// rectifies it into the frame pool, then lends the newest pair to every
// attached frame consumer (the visual odometry, a mapper; frame_consumer.hpp)
// by handle, never by copy. Its health crosses to the loop through a
// SeqLatch; its preview and camera info go out on the publisher thread.
//
// With a consumer attached at creation, a step also takes the frames the
// device has already captured (the driver's catch-up): when a consumer falls
// behind, the frames in between are rectified and published but not handed
// on (each consumer counts them as skipped), so the latency never grows past
// one frame and the kernel never runs out of buffers. A replay makes the
// same dequeues, so it skips the same frames.
#include <atomic>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "core/seq_cell.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "runtime/devices/camera/camera_outputs.hpp"
#include "runtime/devices/frame_consumer.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/device_buses.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

// The driver's config from [camera]: the factory calibration is loaded here
// (start-up), with the file, line and key of anything wrong in it.
bool camera_driver_config(const CameraSection& c, drivers::StereoCameraConfig* out, std::string* error);

extern const char* const kCameraKeys[13];

class CameraDevice final : public Device, public FrameSource {
 public:
  static constexpr int kMaxConsumers = 4;

  // The configuration is the core's; buses.video and buses.clock are
  // required. catch_up: take every captured frame each step and hand the
  // newest on (a consumer will be attached).
  static std::unique_ptr<CameraDevice> create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                              bool catch_up, std::string* error);

  void step(TimeNs timeout_ns) noexcept override;
  // The first consumer that feeds a sensor: its sensor and samples (a
  // replay steps the camera until the loop's intake); else no sensor and
  // the frames published.
  int sensor() const noexcept override { return fed_ != nullptr ? fed_->sensor() : -1; }
  std::int64_t samples() const noexcept override {
    return fed_ != nullptr ? fed_->samples() : frames_.load(std::memory_order_acquire);
  }
  void fill_snapshot(Snapshot& s) noexcept override;
  void publish_due(TimeNs now, transport::MessageSink& sink) noexcept override;
  FrameSource* frame_source() noexcept override { return this; }

  // FrameSource.
  bool attach(FrameConsumer& consumer, std::string* error) override;
  FramePool& pool() noexcept override { return *pool_; }
  const drivers::StereoRectification& rectified() const noexcept override { return camera_->rectified(); }
  hal::Clock& clock() noexcept override { return *clock_; }

  const drivers::StereoCameraStats& stats() const { return camera_->stats(); }  // camera thread only
  std::int64_t frames() const noexcept { return frames_.load(std::memory_order_acquire); }

 private:
  CameraDevice(FusionCore& core, int device_slot) : core_(core), slot_(device_slot) {}

  // What the camera thread shares with the loop.
  struct Health {
    drivers::StereoCameraStats stats;
    drivers::StereoStepOutcome last = drivers::StereoStepOutcome::kTimeout;
  };

  FusionCore& core_;
  hal::Clock* clock_ = nullptr;
  int slot_ = -1;
  // No frame for this long on the loop's clock and the camera is reported
  // stalled, whatever its thread last said: a device that stops delivering
  // without the driver noticing (a stall shorter than the dequeue timeout
  // each time, a thread that hangs) still shows.
  TimeNs stall_after_ns_ = 0;
  std::unique_ptr<FramePool> pool_;
  std::unique_ptr<drivers::StereoCamera> camera_;
  std::unique_ptr<CameraOutputs> outputs_;  // publisher thread
  drivers::StereoFrameResult result_;
  FrameConsumer* consumers_[kMaxConsumers] = {};
  int num_consumers_ = 0;
  int frames_held_ = 0;                // by the attached consumers, beyond their calls
  FrameConsumer* fed_ = nullptr;       // the first consumer feeding a sensor
  std::uint64_t last_lent_ = 0;        // the newest frame id handed to the consumers
  Health scratch_;
  SeqLatch<Health> health_;
  std::atomic<std::int64_t> frames_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
