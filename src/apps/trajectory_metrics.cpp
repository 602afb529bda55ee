#include "apps/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace rtfuse::apps {

double rotation_angle_deg(const Eigen::Matrix3d& r) {
  const double c = std::max(-1.0, std::min(1.0, 0.5 * (r.trace() - 1.0)));
  return std::acos(c) * 180.0 / 3.14159265358979323846;
}

std::vector<Eigen::Matrix4d> reanchored(const std::vector<Eigen::Matrix4d>& poses, std::size_t first) {
  std::vector<Eigen::Matrix4d> out;
  if (first >= poses.size()) return out;
  const Eigen::Matrix4d from = poses[first].inverse();
  for (std::size_t i = first; i < poses.size(); ++i) out.push_back(from * poses[i]);
  return out;
}

TrajectoryErrors compare_trajectories(const std::vector<Eigen::Matrix4d>& est, const std::vector<Eigen::Matrix4d>& gt) {
  TrajectoryErrors e;
  const std::size_t n = std::min(est.size(), gt.size());
  e.frames = static_cast<int>(n);
  if (n == 0) return e;
  double sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sq += (est[i].topRightCorner<3, 1>() - gt[i].topRightCorner<3, 1>()).squaredNorm();
    if (i > 0) {
      e.path_length_m += (gt[i].topRightCorner<3, 1>() - gt[i - 1].topRightCorner<3, 1>()).norm();
      const Eigen::Matrix4d de = est[i - 1].inverse() * est[i];
      const Eigen::Matrix4d dg = gt[i - 1].inverse() * gt[i];
      const Eigen::Matrix4d err = dg.inverse() * de;
      e.rpe_translation_m += err.topRightCorner<3, 1>().norm();
      e.rpe_rotation_deg += rotation_angle_deg(err.topLeftCorner<3, 3>());
    }
  }
  if (n > 1) {
    e.rpe_translation_m /= static_cast<double>(n - 1);
    e.rpe_rotation_deg /= static_cast<double>(n - 1);
  }
  e.ate_rmse_m = std::sqrt(sq / static_cast<double>(n));
  e.final_error_m = (est[n - 1].topRightCorner<3, 1>() - gt[n - 1].topRightCorner<3, 1>()).norm();
  e.final_error_pct = e.path_length_m > 0.0 ? 100.0 * e.final_error_m / e.path_length_m : 0.0;
  e.final_rotation_error_deg =
      rotation_angle_deg(gt[n - 1].topLeftCorner<3, 3>().transpose() * est[n - 1].topLeftCorner<3, 3>());
  return e;
}

}  // namespace rtfuse::apps
