#include "runtime/devices/camera/camera_device.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/devices/camera/camera_calibration.hpp"

namespace rtfuse {

// fps_milli: the rate measured from the capture stamps, in 1/1000 fps.
// pairs_digest: StereoCameraStats::pairs_digest's bits as an int64.
const char* const kCameraKeys[13] = {"frames",        "fps_milli",          "dropped",   "sequence_gaps",
                                     "rejected_size", "rejected_corrupted", "pool_full", "timeouts",
                                     "lost",          "reopen_attempts",    "reopens",   "errors",
                                     "pairs_digest"};

bool camera_driver_config(const CameraSection& c, drivers::StereoCameraConfig* out, std::string* error) {
  drivers::ZedCalibration calibration;
  if (!load_camera_calibration(c, c.serial, &calibration, error)) return false;
  drivers::StereoCameraConfig d;
  d.resolution = std::string(c.resolution.view());
  d.fps = c.fps;
  d.expected_serial = c.serial;
  d.calibration_serial = calibration.serial;
  d.calibration = calibration.stereo;
  d.reopen_backoff_initial_ns = sec_to_ns(c.reopen_backoff_s);
  d.reopen_backoff_max_ns = sec_to_ns(c.reopen_backoff_max_s);
  *out = d;
  return true;
}

std::unique_ptr<CameraDevice> CameraDevice::create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                                   bool catch_up, std::string* error) {
  if (buses.video == nullptr || buses.clock == nullptr) {
    *error = "[camera] is configured but the HAL has no video stream";
    return nullptr;
  }
  const CameraSection& c = core.config().hardware.camera;
  drivers::StereoCameraConfig dcfg;
  if (!camera_driver_config(c, &dcfg, error)) return nullptr;
  // A consumer takes the newest pair of each step: catching up on frames
  // already captured keeps it on the newest one when it falls behind.
  if (catch_up) dcfg.max_frames_per_step = std::max(1, c.buffers);
  std::unique_ptr<CameraDevice> d(new CameraDevice(core, device_slot));
  d->clock_ = buses.clock;
  // Five frame periods, and never under 200 ms (USB hiccups at 100 fps).
  d->stall_after_ns_ = std::max<TimeNs>(5 * 1'000'000'000LL / std::max(1, c.fps), 200'000'000);
  d->pool_ = std::make_unique<FramePool>(c.pool_frames, dcfg.calibration.width, dcfg.calibration.height);
  d->camera_ = drivers::StereoCamera::create(dcfg, *buses.video, *buses.clock, *d->pool_, error);
  if (!d->camera_) {
    *error = "camera " + std::string(c.device.view()) + ": " + *error;
    return nullptr;
  }
  d->outputs_ = CameraOutputs::create(*d->pool_, d->camera_->rectified(), c, error);
  if (!d->outputs_) return nullptr;
  d->health_.store(d->scratch_);
  return d;
}

bool CameraDevice::attach(FrameConsumer& consumer, std::string* error) {
  if (num_consumers_ == kMaxConsumers) {
    *error = std::string("camera: no room for frame consumer '") + consumer.name() + "': at most " +
             std::to_string(kMaxConsumers);
    return false;
  }
  // Capture needs a slot to fill and the newest pair one; the preview holds
  // one while it encodes. What the consumers keep beyond their calls must
  // leave those, or a slow consumer would make capture drop frames.
  const int preview = core_.config().hardware.camera.preview_rate_hz > 0.0 ? 1 : 0;
  const int needed = 2 + preview + frames_held_ + consumer.frames_held();
  if (needed > pool_->slots()) {
    *error = std::string("camera: frame consumer '") + consumer.name() + "' keeps " +
             std::to_string(consumer.frames_held()) + " pair(s), which the pool of " +
             std::to_string(pool_->slots()) + " cannot lend without starving capture: set camera.pool_frames >= " +
             std::to_string(needed);
    return false;
  }
  frames_held_ += consumer.frames_held();
  consumers_[num_consumers_++] = &consumer;
  if (fed_ == nullptr && consumer.sensor() >= 0) fed_ = &consumer;
  return true;
}

void CameraDevice::step(TimeNs timeout_ns) noexcept {
  const drivers::StereoStepOutcome r = camera_->step(timeout_ns, &result_);
  if (result_.published > 0) frames_.fetch_add(result_.published, std::memory_order_acq_rel);
  if (num_consumers_ > 0 && result_.published > 0) {
    FramePool::Handle h = pool_->take_latest(last_lent_);
    if (h.valid()) {
      last_lent_ = h.frame_id;
      for (int i = 0; i < num_consumers_; ++i) consumers_[i]->on_pair(*pool_, h);
      pool_->release(h);
    }
  }
  scratch_.last = r;
  scratch_.stats = camera_->stats();
  health_.store(scratch_);
}

void CameraDevice::publish_due(TimeNs now, transport::MessageSink& sink) noexcept { outputs_->publish_due(now, sink); }

void CameraDevice::fill_snapshot(Snapshot& s) noexcept {
  if (slot_ < 0) return;
  Health h;
  health_.load(h);
  const drivers::StereoCameraStats& st = h.stats;
  DeviceStatus& d = s.devices[slot_];
  set_device_values(d, kCameraKeys,
                    {st.rectified, static_cast<std::int64_t>(std::lround(st.measured_fps() * 1000.0)),
                     st.stream.dropped, st.stream.sequence_gaps, st.rejected_size, st.rejected_corrupted,
                     st.pool_full, st.stream.timeouts, st.lost, st.reopen_attempts, st.stream.reopens, st.errors,
                     // The digest's 64 bits as they are (two's complement).
                     static_cast<std::int64_t>(st.pairs_digest)});
  d.state = drivers::to_string(h.last);
  set_device_message(d.message, st.last_error);
  switch (h.last) {
    case drivers::StereoStepOutcome::kFrame: d.level = DeviceLevel::kOk; break;
    case drivers::StereoStepOutcome::kLost:
    case drivers::StereoStepOutcome::kDown:
    case drivers::StereoStepOutcome::kError: d.level = DeviceLevel::kError; break;
    case drivers::StereoStepOutcome::kTimeout:
      d.level = st.rectified == 0 ? DeviceLevel::kStale : DeviceLevel::kWarn;
      break;
    default: d.level = DeviceLevel::kWarn; break;
  }
  const TimeNs since = s.tick_time_ns - st.rate_last_stamp;
  if (st.rectified > 0 && st.rate_last_stamp > 0 && since > stall_after_ns_ && d.level == DeviceLevel::kOk) {
    d.level = DeviceLevel::kWarn;
    d.state = "stalled";
    char text[96];
    std::snprintf(text, sizeof text, "no frame for %lld ms", static_cast<long long>(since / 1'000'000));
    set_device_message(d.message, text);
  }
}

}  // namespace rtfuse
