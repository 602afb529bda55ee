// sensor_msgs/Imu: up to three measurements (orientation, angular velocity,
// linear acceleration), each with its own rejection threshold.
#include "estimation/sensor_model.hpp"

#include "geometry/rotation.hpp"

namespace rtfuse::est {

SampleRejection SensorModel::convert_imu(const SensorSample& s, const StateVector& state,
                                         const FusionFrames& f, MeasurementBatch* out) noexcept {
  const auto base_T_imu = f.tree->lookup(f.base_link, s.frame);
  if (!base_T_imu) return SampleRejection::kNoTransform;
  const Eigen::Matrix3d r = base_T_imu->rotation_matrix();
  const ImuSample& imu = s.imu;

  if (imu.has_orientation && (sensor_.update_mask & kOrientationMask)) {
    // The IMU reports world_R_imu; the body's attitude is world_R_imu * imu_R_base.
    WorldPose pose;
    pose.t.rotation = (imu.orientation * base_T_imu->rotation.conjugate()).normalized();
    pose.covariance.setZero();
    pose.covariance.bottomRightCorner<3, 3>() = r * imu.orientation_covariance * r.transpose();
    pose_part(s.stamp, pose, sensor_.update_mask & kOrientationMask, out);
  }

  if (imu.has_angular_velocity && (sensor_.update_mask & kAngularVelocityMask)) {
    Measurement m = blank(s.stamp, MeasurementPart::kTwist);
    m.z.segment<3>(kVroll) = r * imu.angular_velocity;
    m.covariance.block<3, 3>(kVroll, kVroll) = r * imu.angular_velocity_covariance * r.transpose();
    m.mask = sensor_.update_mask & kAngularVelocityMask;
    add(out, m);
  }

  if (imu.has_linear_acceleration && (sensor_.update_mask & kAccelerationMask)) {
    Eigen::Vector3d a = imu.linear_acceleration;
    if (sensor_.remove_gravitational_acceleration) {
      // Gravity seen in the IMU frame; attitude from the message when it has
      // one, else from the filter (as robot_localization).
      Eigen::Quaterniond world_q_imu;
      if (imu.has_orientation) {
        world_q_imu = imu.orientation;
      } else {
        world_q_imu = geometry::quaternion_from_rpy(state(kRoll), state(kPitch), state(kYaw)) *
                      base_T_imu->rotation;
      }
      a -= world_q_imu.conjugate() * Eigen::Vector3d(0.0, 0.0, gravity_);
    }
    Measurement m = blank(s.stamp, MeasurementPart::kAcceleration);
    m.z.segment<3>(kAx) = r * a;
    m.covariance.block<3, 3>(kAx, kAx) = r * imu.linear_acceleration_covariance * r.transpose();
    m.mask = sensor_.update_mask & kAccelerationMask;
    add(out, m);
  }
  return SampleRejection::kNone;
}

}  // namespace rtfuse::est
