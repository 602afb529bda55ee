#include "runtime/camera_device.hpp"

#include <cmath>

#include "runtime/camera_calibration.hpp"

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
                                                   std::string* error) {
  if (buses.video == nullptr || buses.clock == nullptr) {
    *error = "[camera] is configured but the HAL has no video stream";
    return nullptr;
  }
  const CameraSection& c = core.config().hardware.camera;
  drivers::StereoCameraConfig dcfg;
  if (!camera_driver_config(c, &dcfg, error)) return nullptr;
  std::unique_ptr<CameraDevice> d(new CameraDevice(device_slot));
  d->pool_ = std::make_unique<FramePool>(c.pool_frames, dcfg.calibration.width, dcfg.calibration.height);
  d->camera_ = drivers::StereoCamera::create(dcfg, *buses.video, *buses.clock, *d->pool_, error);
  if (!d->camera_) {
    *error = "camera " + std::string(c.device.view()) + ": " + *error;
    return nullptr;
  }
  d->health_.store(d->scratch_);
  return d;
}

void CameraDevice::step(TimeNs timeout_ns) noexcept {
  const drivers::StereoStepOutcome r = camera_->step(timeout_ns, &result_);
  if (result_.published > 0) frames_.fetch_add(result_.published, std::memory_order_acq_rel);
  scratch_.last = r;
  scratch_.stats = camera_->stats();
  health_.store(scratch_);
}

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
}

}  // namespace rtfuse
