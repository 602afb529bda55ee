#pragma once
// robot_localization's omnidirectional kinematic model: constant acceleration
// in the body frame, pose integrated through the current attitude.
#include "estimation/state.hpp"

namespace rtfuse::est {

// x <- f(x, dt). Angles are wrapped by the caller.
void motion_model_predict(StateVector& x, double dt) noexcept;

// The 9 non-trivial rows of df/dx (rows x..vz); rows vroll..az are identity.
// Kept separate so the covariance propagation can skip the identity part,
// and the structural zeros and ones below: pos_rpy(2, 2) = 0 (height does not
// depend on yaw), rpy_rpy(0..1, 2) = 0 and rpy_rpy(1, 1) = rpy_rpy(2, 2) = 1
// (no Euler rate depends on yaw, pitch's and yaw's rows keep themselves),
// rpy_rate(1..2, 0) = 0 (body roll rate moves roll only).
struct MotionJacobian {
  Eigen::Matrix3d pos_rpy;   // d(position)/d(roll, pitch, yaw)
  Eigen::Matrix3d pos_vel;   // R * dt; d(position)/d(acceleration) is pos_vel * dt / 2
  Eigen::Matrix3d rpy_rpy;   // d(rpy)/d(rpy), identity included
  Eigen::Matrix3d rpy_rate;  // Euler-rate matrix * dt
  double vel_acc = 0.0;      // dt (d v / d a is dt * I)
};

MotionJacobian motion_model_jacobian(const StateVector& x, double dt) noexcept;

// Both at once, sharing the trigonometry (the filter's hot path): returns the
// Jacobian at the prior x and advances x.
MotionJacobian motion_model_step(StateVector& x, double dt) noexcept;

// The same Jacobian as a dense matrix, for tests and readers.
StateMatrix motion_model_jacobian_dense(const StateVector& x, double dt) noexcept;

}  // namespace rtfuse::est
