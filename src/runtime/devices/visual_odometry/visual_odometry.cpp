#include "runtime/devices/visual_odometry/visual_odometry.hpp"

#include <algorithm>
#include <cmath>

#include "vision/egomotion_twist.hpp"

namespace rtfuse {

vision::StereoOdometryParams stereo_odometry_params(const VoSection& vo) noexcept {
  vision::StereoOdometryParams p;
  p.half_resolution = vo.half_resolution;
  p.bucket_size_px = vo.bucket_size_px;
  p.bucket_max = vo.bucket_max;
  p.egomotion.ransac_iterations = vo.ransac_iterations;
  p.egomotion.inlier_threshold_px = vo.inlier_threshold_px;
  p.egomotion.min_inliers = vo.min_inliers;
  return p;
}

std::unique_ptr<VisualOdometry> VisualOdometry::create(const VoSection& vo, const drivers::StereoRectification& camera,
                                                       int sensor, int frame, std::string* error) {
  // The odometry's pinhole has one focal length; the rectification gives
  // both eyes the same, and fx = fy unless the sensor's pixels are not square.
  if (!(camera.fx > 0.0) || std::abs(camera.fx - camera.fy) > 1e-6 * camera.fx) {
    *error = "visual odometry needs square rectified pixels (fx = fy), the camera's rectification has fx " +
             std::to_string(camera.fx) + " and fy " + std::to_string(camera.fy);
    return nullptr;
  }
  if (!(camera.baseline_m > 0.0) || camera.width < 64 || camera.height < 64) {
    *error = "visual odometry needs a stereo baseline > 0 and eyes of at least 64x64 pixels";
    return nullptr;
  }
  std::unique_ptr<VisualOdometry> v(new VisualOdometry(vo, sensor, frame));
  const vision::StereoCameraModel model{camera.fx, camera.cx, camera.cy, camera.baseline_m};
  v->odometry_ = std::make_unique<vision::StereoOdometry>(camera.width, camera.height, model, stereo_odometry_params(vo));
  return v;
}

void VisualOdometry::set_time(TimeNs cpu_ns) noexcept {
  stats_.last_time_ns = cpu_ns;
  stats_.max_time_ns = std::max(stats_.max_time_ns, cpu_ns);
}

bool VisualOdometry::process(const FramePool::Frame& pair, est::SensorSample* out) noexcept {
  VoStats& st = stats_;
  // A long gap (lost frames, a replugged camera) or time going backwards:
  // the previous pair is no reference for this one.
  if (have_previous_ &&
      (pair.stamp <= previous_stamp_ || pair.stamp - previous_stamp_ > sec_to_ns(vo_.max_interval_s))) {
    odometry_->reset();
    ++st.restarts;
  }
  const vision::GreyView left{pair.left, pair.width, pair.height, pair.stride};
  const vision::GreyView right{pair.right, pair.width, pair.height, pair.stride};
  const TimeNs previous = previous_stamp_;
  const vision::StereoOdometryResult r = odometry_->process(left, right, pair.frame_id);
  ++st.pairs;
  have_previous_ = true;
  previous_stamp_ = pair.stamp;
  st.last_status = r.status;
  st.last_matches = r.bucketed;
  st.last_inliers = r.motion.inliers;
  st.last_residual_px = r.motion.residual_rms_px;
  switch (r.status) {
    case vision::VoStatus::kMotion: break;
    case vision::VoStatus::kTooFewMatches: ++st.too_few_matches; return false;
    case vision::VoStatus::kNoConsensus: ++st.no_consensus; return false;
    case vision::VoStatus::kFirstFrame: return false;
    case vision::VoStatus::kBadInput: ++st.implausible; return false;
  }
  const double dt = ns_to_sec(pair.stamp - previous);
  const vision::CameraTwist twist = vision::egomotion_twist(r.motion, dt);
  if (!twist.ok || !(twist.linear.norm() <= vo_.max_speed_mps) || !(twist.angular.norm() <= vo_.max_turn_rate_rad_s)) {
    ++st.implausible;
    // A wrong motion also makes a wrong prediction for the next pair.
    odometry_->reset();
    have_previous_ = false;
    return false;
  }
  est::SensorSample& s = *out;
  s.stamp = previous + (pair.stamp - previous) / 2;
  s.sensor = static_cast<std::uint8_t>(sensor_);
  s.kind = est::SensorKind::kTwist;
  s.frame = static_cast<std::int16_t>(frame_);
  s.child_frame = -1;
  s.twist.linear = twist.linear;
  s.twist.angular = twist.angular;
  est::Matrix6 c = twist.covariance * vo_.covariance_scale;
  const double floor_v = vo_.min_linear_sigma_mps * vo_.min_linear_sigma_mps;
  const double floor_w = vo_.min_angular_sigma_rad_s * vo_.min_angular_sigma_rad_s;
  for (int i = 0; i < 6; ++i) c(i, i) += i < 3 ? floor_v : floor_w;
  s.twist.covariance = c;
  ++st.motions;
  if (st.rate_count == 0) st.rate_first_stamp = pair.stamp;
  st.rate_last_stamp = pair.stamp;
  ++st.rate_count;
  return true;
}

}  // namespace rtfuse
