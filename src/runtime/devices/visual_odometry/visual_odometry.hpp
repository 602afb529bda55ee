#pragma once
// Stereo visual odometry on the camera's thread: every rectified pair it is
// given becomes (after the first) the left eye's twist over the interval
// since the pair before, pushed as a twist sample of camera.frame into the
// [[sensor]] with source = "stereo_vo". The filter brings it to base_link
// through the mount in the frame tree, like any twist sensor.
//
// The sample is stamped at the middle of the interval: a frame-to-frame
// motion is the average velocity between the two exposures, which is the
// velocity at the midpoint to second order. It reaches the loop tens of
// milliseconds later (exposure, readout, rectification, this work); the
// filter's lagged-data history fuses it where it belongs
// ([filter] smooth_lagged_data, history_length).
//
// Allocates in create() only. The work of process() is bounded by the
// workspace sized from the image (vision/stereo_odometry.hpp).
#include <cstdint>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "estimation/sensor_sample.hpp"
#include "runtime/config/hardware_config.hpp"
#include "vision/stereo_odometry.hpp"

namespace rtfuse {

struct VoStats {
  std::int64_t pairs = 0;          // processed
  std::int64_t motions = 0;        // measurements pushed
  std::int64_t skipped = 0;        // published while the odometry was busy: not processed
  std::int64_t too_few_matches = 0;
  std::int64_t no_consensus = 0;
  std::int64_t implausible = 0;    // beyond max_speed / max_turn_rate, or not finite
  std::int64_t restarts = 0;       // a gap over max_interval, or a frame out of order
  int last_matches = 0;
  int last_inliers = 0;
  double last_residual_px = 0.0;
  TimeNs last_time_ns = 0;         // processing time of the last pair (CPU of the camera thread)
  TimeNs max_time_ns = 0;
  // From the pair's capture to its twist in the ring, the last pair's, on
  // the camera's clock.
  TimeNs last_latency_ns = 0;
  // Rate of measurements from the capture stamps.
  TimeNs rate_first_stamp = 0;
  TimeNs rate_last_stamp = 0;
  std::int64_t rate_count = 0;
  double measured_hz() const noexcept {
    if (rate_count < 2 || rate_last_stamp <= rate_first_stamp) return 0.0;
    return static_cast<double>(rate_count - 1) * 1e9 / static_cast<double>(rate_last_stamp - rate_first_stamp);
  }
  vision::VoStatus last_status = vision::VoStatus::kFirstFrame;
};

// [vo] as the vision layer's parameters.
vision::StereoOdometryParams stereo_odometry_params(const VoSection& vo) noexcept;

class VisualOdometry {
 public:
  // For pairs of the rectified camera; sensor: the stereo_vo sensor's index,
  // frame: camera.frame's index in the frame tree. Null with *error when
  // the rectified camera cannot be used (unequal focal lengths, no baseline).
  static std::unique_ptr<VisualOdometry> create(const VoSection& vo, const drivers::StereoRectification& camera,
                                                int sensor, int frame, std::string* error);

  // One pair: true with *out set when it gives a measurement. Never
  // allocates; counts what it rejects.
  bool process(const FramePool::Frame& pair, est::SensorSample* out) noexcept;
  void count_skipped(std::int64_t n) noexcept { stats_.skipped += n; }
  void set_time(TimeNs cpu_ns) noexcept;
  void set_latency(TimeNs ns) noexcept { stats_.last_latency_ns = ns; }

  const VoStats& stats() const noexcept { return stats_; }

 private:
  VisualOdometry(const VoSection& vo, int sensor, int frame) : vo_(vo), sensor_(sensor), frame_(frame) {}

  VoSection vo_;
  int sensor_ = 0;
  int frame_ = -1;
  std::unique_ptr<vision::StereoOdometry> odometry_;
  bool have_previous_ = false;
  TimeNs previous_stamp_ = 0;
  VoStats stats_;
};

}  // namespace rtfuse
