#pragma once
// a_T_b: the pose of frame b expressed in frame a, so p_a = a_T_b * p_b.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rtfuse::geometry {

struct RigidTransform {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  static RigidTransform identity() { return {}; }

  RigidTransform inverse() const {
    RigidTransform t;
    t.rotation = rotation.conjugate();
    t.translation = -(t.rotation * translation);
    return t;
  }
  RigidTransform operator*(const RigidTransform& o) const {
    RigidTransform t;
    t.rotation = rotation * o.rotation;
    t.translation = translation + rotation * o.translation;
    return t;
  }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  Eigen::Matrix3d rotation_matrix() const { return rotation.toRotationMatrix(); }
  bool is_identity(double tol = 1e-12) const {
    return translation.norm() <= tol && std::abs(std::abs(rotation.w()) - 1.0) <= tol;
  }
};

}  // namespace rtfuse::geometry
