#include "estimation/sensor_model.hpp"

#include <cmath>

#include "geometry/rotation.hpp"

namespace rtfuse::est {

Matrix6 rotate_covariance6(const Matrix6& c, const Eigen::Matrix3d& r) noexcept {
  Matrix6 rot = Matrix6::Zero();
  rot.topLeftCorner<3, 3>() = r;
  rot.bottomRightCorner<3, 3>() = r;
  return rot * c * rot.transpose();
}

SensorModel::SensorModel(std::uint8_t index, const SensorParams& sensor, const FilterParams& filter)
    : index_(index),
      sensor_(sensor),
      two_d_(filter.two_d_mode),
      gravity_(filter.gravity),
      navsat_(sensor.navsat) {}

void SensorModel::reset() noexcept {
  has_reference_ = false;
  has_previous_ = false;
}

bool SensorModel::fuses_absolute_yaw() const noexcept {
  return mask_has(sensor_.update_mask, kYaw) && !sensor_.differential &&
         sensor_.kind != SensorKind::kTwist;
}

Measurement SensorModel::blank(TimeNs stamp, MeasurementPart part) const noexcept {
  Measurement m;
  m.stamp = stamp;
  m.sensor = index_;
  m.part = part;
  switch (part) {
    case MeasurementPart::kPose: m.mahalanobis_threshold = sensor_.pose_rejection_threshold; break;
    case MeasurementPart::kTwist: m.mahalanobis_threshold = sensor_.twist_rejection_threshold; break;
    case MeasurementPart::kAcceleration:
      m.mahalanobis_threshold = sensor_.linear_acceleration_rejection_threshold;
      break;
  }
  return m;
}

void SensorModel::add(MeasurementBatch* out, const Measurement& in) const noexcept {
  if (out->count >= 3) return;
  Measurement& m = out->items[out->count];
  m = in;
  if (two_d_) {
    // two_d_mode: the 3D variables of this part are measured as exactly 0,
    // which holds the planar robot on the plane whatever the sensors say.
    UpdateMask forced = 0;
    if (m.part == MeasurementPart::kPose) forced = mask_bit(kZ) | mask_bit(kRoll) | mask_bit(kPitch);
    if (m.part == MeasurementPart::kTwist) forced = mask_bit(kVz) | mask_bit(kVroll) | mask_bit(kVpitch);
    if (m.part == MeasurementPart::kAcceleration) forced = mask_bit(kAz);
    for (int i = 0; i < kStateSize; ++i) {
      if (!mask_has(forced, i)) continue;
      m.z(i) = 0.0;
      m.covariance.row(i).setZero();
      m.covariance.col(i).setZero();
      m.covariance(i, i) = 1e-9;
    }
    m.mask |= forced;
  }
  if (m.mask == 0) return;
  if (m.part == MeasurementPart::kPose && mask_has(m.mask, kYaw)) m.yaw_gate_sigma = yaw_gate_sigma_;
  ++out->count;
}

SampleRejection SensorModel::convert(const SensorSample& s, const StateVector& state,
                                     const FusionFrames& frames, MeasurementBatch* out) noexcept {
  out->count = 0;
  switch (s.kind) {
    case SensorKind::kOdometry: {
      if (sensor_.kind != SensorKind::kOdometry) return SampleRejection::kWrongKind;
      SampleRejection r = SampleRejection::kNone;
      if (sensor_.update_mask & kPoseMask) r = convert_pose(s, frames, out);
      if (r != SampleRejection::kNone) return r;
      if (sensor_.update_mask & kTwistMask) {
        // nav_msgs/Odometry: the twist is given in child_frame_id.
        const int frame = s.child_frame >= 0 ? s.child_frame : frames.base_link;
        r = convert_twist(s, frame, state, frames, out);
      }
      return r;
    }
    case SensorKind::kPose:
      if (sensor_.kind != SensorKind::kPose) return SampleRejection::kWrongKind;
      return convert_pose(s, frames, out);
    case SensorKind::kTwist:
      if (sensor_.kind != SensorKind::kTwist) return SampleRejection::kWrongKind;
      return convert_twist(s, s.frame, state, frames, out);
    case SensorKind::kImu:
      if (sensor_.kind != SensorKind::kImu) return SampleRejection::kWrongKind;
      return convert_imu(s, state, frames, out);
    case SensorKind::kNavSatFix:
      if (sensor_.kind != SensorKind::kNavSatFix) return SampleRejection::kWrongKind;
      return convert_navsat(s, state, out);
  }
  return SampleRejection::kWrongKind;
}

void SensorModel::pose_part(TimeNs stamp, const WorldPose& pose_in, UpdateMask mask,
                            MeasurementBatch* out) noexcept {
  WorldPose pose = pose_in;
  if (sensor_.relative) {
    // The first pose becomes the origin; later ones are measured from it.
    if (!has_reference_) {
      reference_ = pose.t;
      has_reference_ = true;
    }
    pose.t = reference_.inverse() * pose.t;
  }

  if (sensor_.differential) {
    // robot_localization's differential mode: consecutive poses become a
    // body-frame velocity, so a drifting absolute source only adds motion.
    const bool have_previous = has_previous_;
    const WorldPose previous = previous_;
    const TimeNs previous_stamp = previous_stamp_;
    previous_ = pose;
    previous_stamp_ = stamp;
    has_previous_ = true;
    if (!have_previous) return;
    const double dt = ns_to_sec(stamp - previous_stamp);
    if (!(dt > 0.0)) return;
    const geometry::RigidTransform delta = previous.t.inverse() * pose.t;
    const Eigen::Vector3d rpy = geometry::rpy_from_quaternion(delta.rotation);
    Measurement m = blank(stamp, MeasurementPart::kTwist);
    m.z.segment<3>(kVx) = delta.translation / dt;
    m.z.segment<3>(kVroll) = rpy / dt;
    const Eigen::Matrix3d world_to_body = previous.t.rotation_matrix().transpose();
    m.covariance.block<6, 6>(kVx, kVx) =
        rotate_covariance6(previous.covariance + pose.covariance, world_to_body) / (dt * dt);
    m.mask = static_cast<UpdateMask>((mask & kPoseMask) << kVx);
    add(out, m);
    return;
  }

  Measurement m = blank(stamp, MeasurementPart::kPose);
  m.z.segment<3>(kX) = pose.t.translation;
  m.z.segment<3>(kRoll) = geometry::rpy_from_quaternion(pose.t.rotation);
  m.covariance.block<6, 6>(kX, kX) = pose.covariance;
  m.mask = mask & kPoseMask;
  add(out, m);
}

}  // namespace rtfuse::est
