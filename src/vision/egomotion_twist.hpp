#pragma once
// The stereo camera's velocity from one egomotion, for a filter that fuses
// twists: the constant body-frame twist that carries the previous left
// camera onto the current one in dt, i.e. the SE(3) logarithm of the
// camera's motion divided by dt. A twist rather than a pose increment
// because the filter fuses velocities of sensors at a lever arm
// (robot_localization's twist semantics), and a frame-to-frame motion is
// exactly an average velocity over the interval.
//
// Its covariance is the egomotion's pushed through the Jacobian of that map,
// taken by central differences (12 evaluations of a few dozen flops): exact
// enough for a covariance and free of a hand-derived SE(3) Jacobian.
//
// Only sin, cos, atan2 and sqrt: portable bits on every architecture.
#include <Eigen/Core>

#include "vision/stereo_egomotion.hpp"

namespace rtfuse::vision {

struct CameraTwist {
  bool ok = false;
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   // m/s, the camera's own axes
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  // rad/s, the camera's own axes
  // Over vx vy vz wx wy wz (the order of a TwistWithCovariance).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

// dt_s > 0. Not ok for a failed egomotion, a rotation of more than a
// quarter turn between the frames, or a non-finite result.
CameraTwist egomotion_twist(const Egomotion& motion, double dt_s) noexcept;

// The body-frame twist times dt of x_cur = T x_prev (T from egomotion
// params): angular then linear, each 3. Exposed for tests.
Eigen::Matrix<double, 6, 1> egomotion_log(const Eigen::Matrix<double, 6, 1>& params) noexcept;

}  // namespace rtfuse::vision
