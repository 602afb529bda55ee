#include "runtime/devices/camera/camera_device.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/devices/camera/camera_calibration.hpp"

namespace rtfuse {

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

std::unique_ptr<CameraDevice> CameraDevice::create(const CameraBuses& buses, FusionCore& core, int device_slot,
                                                   int vo_slot, std::string* error) {
  if (buses.video == nullptr || buses.clock == nullptr) {
    *error = "[camera] is configured but the HAL has no video stream";
    return nullptr;
  }
  const CameraSection& c = core.config().hardware.camera;
  drivers::StereoCameraConfig dcfg;
  if (!camera_driver_config(c, &dcfg, error)) return nullptr;
  const RuntimeConfig& cfg = core.config();
  const VoSection& vo = cfg.hardware.vo;
  // The odometry takes the newest pair of each step: catching up on frames
  // already captured keeps it on the newest one when it falls behind.
  if (vo.enabled) dcfg.max_frames_per_step = std::max(1, c.buffers);
  std::unique_ptr<CameraDevice> d(new CameraDevice(core, device_slot, vo_slot));
  d->clock_ = buses.clock;
  // Five frame periods, and never under 200 ms (USB hiccups at 100 fps).
  d->stall_after_ns_ = std::max<TimeNs>(5 * 1'000'000'000LL / std::max(1, c.fps), 200'000'000);
  d->pool_ = std::make_unique<FramePool>(c.pool_frames, dcfg.calibration.width, dcfg.calibration.height);
  d->camera_ = drivers::StereoCamera::create(dcfg, *buses.video, *buses.clock, *d->pool_, error);
  if (!d->camera_) {
    *error = "camera " + std::string(c.device.view()) + ": " + *error;
    return nullptr;
  }
  if (vo.enabled && cfg.hardware.vo_sensor >= 0) {
    const int frame = core.frames().find(c.frame.view());
    if (frame < 0 || !core.frames().lookup(cfg.base_link_frame.view(), c.frame.view())) {
      *error = "camera.frame '" + std::string(c.frame.view()) + "' is not connected to '" +
               std::string(cfg.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
               std::string(cfg.base_link_frame.view()) + "' and child = '" + std::string(c.frame.view()) +
               "' (the left eye's optical frame: x right, y down, z forward)";
      return nullptr;
    }
    d->vo_sensor_ = cfg.hardware.vo_sensor;
    d->vo_ = VisualOdometry::create(vo, d->camera_->rectified(), d->vo_sensor_, frame, error);
    if (!d->vo_) return nullptr;
  }
  d->health_.store(d->scratch_);
  return d;
}

void CameraDevice::step(TimeNs timeout_ns) noexcept {
  const drivers::StereoStepOutcome r = camera_->step(timeout_ns, &result_);
  if (result_.published > 0) frames_.fetch_add(result_.published, std::memory_order_acq_rel);
  if (vo_ && result_.published > 0) run_odometry();
  scratch_.last = r;
  scratch_.stats = camera_->stats();
  if (vo_) scratch_.vo = vo_->stats();
  health_.store(scratch_);
}

void CameraDevice::run_odometry() noexcept {
  FramePool::Handle h = pool_->take_latest(vo_frame_);
  if (!h.valid()) return;
  const FramePool::Frame f = pool_->frame(h);
  // Published since the last pair the odometry took, other than this one.
  vo_->count_skipped(static_cast<std::int64_t>(f.frame_id - vo_frame_) - 1);
  vo_frame_ = f.frame_id;
  const TimeNs start = monotonic_now_ns();
  const bool measured = vo_->process(f, &sample_);
  const TimeNs done = monotonic_now_ns();
  vo_->set_time(done - start);
  pool_->release(h);
  if (measured) {
    // On the camera's own clock, the one its stamps are on (live: the
    // monotonic clock; a lockstep drive: the simulated one, where no time
    // passes within a step; a replay: the tick being replayed).
    vo_->set_latency(clock_->now() - f.stamp);
    core_.input().push_from_driver(vo_sensor_, sample_);
    vo_samples_.fetch_add(1, std::memory_order_acq_rel);
  }
}

namespace {

void fill_odometry(DeviceStatus& d, const VoStats& v) noexcept {
  set_device_values(d, kVoKeys, kVoKeyCount,
                    {v.pairs, v.motions, static_cast<std::int64_t>(std::lround(v.measured_hz() * 1000.0)), v.skipped,
                     v.too_few_matches, v.no_consensus, v.implausible, v.restarts, v.last_matches, v.last_inliers,
                     static_cast<std::int64_t>(std::lround(v.last_residual_px * 1000.0)), v.last_time_ns / 1000,
                     v.max_time_ns / 1000, v.last_latency_ns / 1000});
  d.state = vision::to_string(v.last_status);
  switch (v.last_status) {
    case vision::VoStatus::kMotion: d.level = DeviceLevel::kOk; break;
    case vision::VoStatus::kFirstFrame: d.level = v.pairs == 0 ? DeviceLevel::kStale : DeviceLevel::kOk; break;
    default: d.level = DeviceLevel::kWarn; break;
  }
}

}  // namespace

void CameraDevice::fill_snapshot(Snapshot& s) noexcept {
  if (slot_ < 0) return;
  Health h;
  health_.load(h);
  const drivers::StereoCameraStats& st = h.stats;
  DeviceStatus& d = s.devices[slot_];
  set_device_values(d, kCameraKeys, kCameraKeyCount,
                    {st.rectified, static_cast<std::int64_t>(std::lround(st.measured_fps() * 1000.0)),
                     st.stream.dropped, st.stream.sequence_gaps, st.rejected_size, st.rejected_corrupted,
                     st.pool_full, st.stream.timeouts, st.lost, st.reopen_attempts, st.stream.reopens, st.errors,
                     // The digest's 64 bits as they are (two's complement).
                     static_cast<std::int64_t>(st.pairs_digest)});
  d.state = drivers::to_string(h.last);
  set_device_message(d.message, st.last_error);
  if (vo_slot_ >= 0 && vo_) fill_odometry(s.devices[vo_slot_], h.vo);
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
