// GNSS fixes (sensor_msgs/NavSatFix): through the navsat transform into a
// position of base_link in the world frame, fused as a pose source whose
// configuration selects x, y (and z).
#include "estimation/sensor_model.hpp"
#include "geometry/rotation.hpp"

namespace rtfuse::est {

SampleRejection SensorModel::convert_navsat(const SensorSample& s, const StateVector& state,
                                            MeasurementBatch* out) noexcept {
  // The filter's pose at the fix's epoch: the datum anchors at it, and its
  // orientation takes the lever arm off.
  geometry::RigidTransform world_T_base;
  world_T_base.translation = state.segment<3>(kX);
  world_T_base.rotation = geometry::quaternion_from_rpy(state(kRoll), state(kPitch), state(kYaw));
  if (sensor_.navsat.use_filter_yaw && !navsat_.has_transform()) navsat_.set_heading(world_T_base.rotation);
  PoseSample fix;
  if (navsat_.convert(s.stamp, s.navsat, world_T_base, &fix) != NavsatRejection::kNone) {
    return SampleRejection::kNavsat;
  }
  WorldPose pose;
  pose.t.translation = fix.position;
  pose.covariance = fix.covariance;
  pose_part(s.stamp, pose, sensor_.update_mask, out);
  return SampleRejection::kNone;
}

}  // namespace rtfuse::est
