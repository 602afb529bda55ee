#include "runtime/devices/visual_odometry/visual_odometry_device.hpp"

#include <cmath>

#include "runtime/devices/device_registry.hpp"

namespace rtfuse {

// fps_milli: measurements per second from the capture stamps, x1000;
// residual_milli_px: the last motion's inlier RMS, 1/1000 px; time_us: the
// last pair's processing time on the camera thread, and the most so far;
// latency_us: the last twist's age when pushed (capture to ring).
const char* const kVoKeys[14] = {"pairs",        "motions",     "fps_milli", "skipped",     "too_few_matches",
                                 "no_consensus", "implausible", "restarts",  "matches",     "inliers",
                                 "residual_milli_px", "time_us", "max_time_us", "latency_us"};

std::unique_ptr<VisualOdometryDevice> VisualOdometryDevice::create(FrameSource& camera, FusionCore& core, int slot,
                                                                   std::string* error) {
  const RuntimeConfig& cfg = core.config();
  const CameraSection& c = cfg.hardware.camera;
  const int frame = core.frames().find(c.frame.view());
  if (frame < 0 || !core.frames().lookup(cfg.base_link_frame.view(), c.frame.view())) {
    *error = "camera.frame '" + std::string(c.frame.view()) + "' is not connected to '" +
             std::string(cfg.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
             std::string(cfg.base_link_frame.view()) + "' and child = '" + std::string(c.frame.view()) +
             "' (the left eye's optical frame: x right, y down, z forward)";
    return nullptr;
  }
  const int sensor = source_sensor(cfg, "stereo_vo");
  std::unique_ptr<VisualOdometryDevice> d(new VisualOdometryDevice(core, camera.clock(), slot, sensor));
  d->vo_ = VisualOdometry::create(cfg.hardware.vo, camera.rectified(), sensor, frame, error);
  if (!d->vo_) return nullptr;
  d->health_.store(d->vo_->stats());
  return d;
}

void VisualOdometryDevice::on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept {
  const FramePool::Frame f = pool.frame(newest);
  // Published since the last pair the odometry took, other than this one.
  vo_->count_skipped(static_cast<std::int64_t>(f.frame_id - last_frame_) - 1);
  last_frame_ = f.frame_id;
  const TimeNs start = monotonic_now_ns();
  const bool measured = vo_->process(f, &sample_);
  const TimeNs done = monotonic_now_ns();
  vo_->set_time(done - start);
  if (measured) {
    // On the camera's own clock, the one its stamps are on (live: the
    // monotonic clock; a lockstep drive: the simulated one, where no time
    // passes within a step; a replay: the tick being replayed).
    vo_->set_latency(clock_.now() - f.stamp);
    core_.input().push_from_driver(sensor_, sample_);
    samples_.fetch_add(1, std::memory_order_acq_rel);
  }
  health_.store(vo_->stats());
}

void VisualOdometryDevice::fill_snapshot(Snapshot& s) noexcept {
  if (slot_ < 0) return;
  VoStats v;
  health_.load(v);
  DeviceStatus& d = s.devices[slot_];
  set_device_values(d, kVoKeys,
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

}  // namespace rtfuse
