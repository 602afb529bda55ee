// Twist sources (nav_msgs/Odometry twist, TwistWithCovarianceStamped): a
// velocity of the sensor frame, brought to base_link including the lever arm.
#include "estimation/sensor_model.hpp"

namespace rtfuse::est {

SampleRejection SensorModel::convert_twist(const SensorSample& s, int twist_frame, const StateVector& state,
                                           const FusionFrames& f, MeasurementBatch* out) noexcept {
  const auto base_T_sensor = f.tree->lookup(f.base_link, twist_frame);
  if (!base_T_sensor) return SampleRejection::kNoTransform;
  const Eigen::Matrix3d r = base_T_sensor->rotation_matrix();
  // A sensor at r_s on a body turning at w moves at v_b + w x r_s, so
  // v_b = R v_s - w x r_s. Like robot_localization, w is the filter's own
  // angular velocity.
  const Eigen::Vector3d w = state.segment<3>(kVroll);

  Measurement m = blank(s.stamp, MeasurementPart::kTwist);
  m.z.segment<3>(kVx) = r * s.twist.linear - w.cross(base_T_sensor->translation);
  m.z.segment<3>(kVroll) = r * s.twist.angular;
  m.covariance.block<6, 6>(kVx, kVx) = rotate_covariance6(s.twist.covariance, r);
  m.mask = sensor_.update_mask & kTwistMask;
  add(out, m);
  return SampleRejection::kNone;
}

}  // namespace rtfuse::est
