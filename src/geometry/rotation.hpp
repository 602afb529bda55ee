#pragma once
// Roll-pitch-yaw conventions of tf2 (rotations about the fixed x, y, z axes,
// applied in that order: R = Rz(yaw) * Ry(pitch) * Rx(roll)).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rtfuse::geometry {

Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw) noexcept;
Eigen::Quaterniond quaternion_from_rpy(double roll, double pitch, double yaw) noexcept;
// Same result as tf2::Matrix3x3::getRPY, including its gimbal-lock branch.
Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& r) noexcept;
Eigen::Vector3d rpy_from_quaternion(const Eigen::Quaterniond& q) noexcept;

}  // namespace rtfuse::geometry
