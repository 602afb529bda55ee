// Pose sources (nav_msgs/Odometry pose, PoseWithCovarianceStamped): the pose
// of child (or base_link) in header.frame_id, brought into world_T_base.
#include "estimation/sensor_model.hpp"

namespace rtfuse::est {

SampleRejection SensorModel::convert_pose(const SensorSample& s, const FusionFrames& f,
                                          MeasurementBatch* out) noexcept {
  const auto world_T_frame = f.tree->lookup(f.world, s.frame);
  if (!world_T_frame) return SampleRejection::kNoTransform;
  geometry::RigidTransform child_T_base;  // identity when the child is base_link
  if (s.child_frame >= 0 && s.child_frame != f.base_link) {
    const auto t = f.tree->lookup(s.child_frame, f.base_link);
    if (!t) return SampleRejection::kNoTransform;
    child_T_base = *t;
  }
  geometry::RigidTransform frame_T_child;
  frame_T_child.translation = s.pose.position;
  frame_T_child.rotation = s.pose.orientation;

  WorldPose pose;
  pose.t = *world_T_frame * frame_T_child * child_T_base;
  pose.covariance = rotate_covariance6(s.pose.covariance, world_T_frame->rotation_matrix());
  pose_part(s.stamp, pose, sensor_.update_mask, out);
  return SampleRejection::kNone;
}

}  // namespace rtfuse::est
