#pragma once
// How far an estimated camera trajectory is from the ground truth, both as
// KITTI poses (camera i -> camera 0, frame 0 the identity): the final
// position and heading errors, the absolute trajectory error without any
// alignment (both start at the identity, as a robot's odometry does), and
// the mean frame-to-frame errors.
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace rtfuse::apps {

struct TrajectoryErrors {
  int frames = 0;
  double path_length_m = 0.0;           // of the ground truth
  double final_error_m = 0.0;
  double final_error_pct = 0.0;         // of the path length
  double final_rotation_error_deg = 0.0;
  double ate_rmse_m = 0.0;
  double rpe_translation_m = 0.0;       // mean per frame
  double rpe_rotation_deg = 0.0;
};

// Over the frames both have (the shorter length).
TrajectoryErrors compare_trajectories(const std::vector<Eigen::Matrix4d>& estimate,
                                      const std::vector<Eigen::Matrix4d>& truth);

// The poses from `first` on, seen from pose `first` (which becomes the
// identity): to judge a stretch of a trajectory on its own, as if the
// odometry had started there. Empty when first is past the end.
std::vector<Eigen::Matrix4d> reanchored(const std::vector<Eigen::Matrix4d>& poses, std::size_t first);

// The rotation angle of a 3x3 rotation, degrees.
double rotation_angle_deg(const Eigen::Matrix3d& r);

}  // namespace rtfuse::apps
