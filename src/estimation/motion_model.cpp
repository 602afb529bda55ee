#include "estimation/motion_model.hpp"

#include <cmath>

namespace rtfuse::est {
namespace {

struct Trig {
  double sr, cr, sp, cp, sy, cy;
};

Trig trig_of(const StateVector& x) noexcept {
  Trig t;
  t.sr = std::sin(x(kRoll));
  t.cr = std::cos(x(kRoll));
  t.sp = std::sin(x(kPitch));
  t.cp = std::cos(x(kPitch));
  t.sy = std::sin(x(kYaw));
  t.cy = std::cos(x(kYaw));
  return t;
}

// Body-to-world rotation, R = Rz(yaw) Ry(pitch) Rx(roll), as tf2.
Eigen::Matrix3d body_to_world(const Trig& t) noexcept {
  Eigen::Matrix3d r;
  r << t.cy * t.cp, t.cy * t.sp * t.sr - t.sy * t.cr, t.cy * t.sp * t.cr + t.sy * t.sr,
       t.sy * t.cp, t.sy * t.sp * t.sr + t.cy * t.cr, t.sy * t.sp * t.cr - t.cy * t.sr,
       -t.sp,       t.cp * t.sr,                      t.cp * t.cr;
  return r;
}

// The position step in the body frame, v dt + a dt^2 / 2. R times it moves
// the position, and the Jacobian's attitude columns are cross products with
// both, so the callers compute it once.
Eigen::Vector3d body_step(const StateVector& x, double dt) noexcept {
  return x.segment<3>(kVx) * dt + 0.5 * dt * dt * x.segment<3>(kAx);
}

void predict_with(const Trig& t, const Eigen::Vector3d& step, StateVector& x, double dt) noexcept {
  const double tp = t.sp / t.cp;
  const double vr = x(kVroll), vp = x(kVpitch), vy = x(kVyaw);

  x.segment<3>(kX) += step;
  // Body rates to Euler-angle rates (singular at pitch = ±pi/2, as in robot_localization).
  x(kRoll) += (vr + t.sr * tp * vp + t.cr * tp * vy) * dt;
  x(kPitch) += (t.cr * vp - t.sr * vy) * dt;
  x(kYaw) += (t.sr / t.cp * vp + t.cr / t.cp * vy) * dt;
  x.segment<3>(kVx) += x.segment<3>(kAx) * dt;
}

// s is body_step(x, dt), step = R s.
MotionJacobian jacobian_with(const Trig& t, const Eigen::Matrix3d& r, const Eigen::Vector3d& s,
                             const Eigen::Vector3d& step, const StateVector& x, double dt) noexcept {
  const double vp = x(kVpitch), vy = x(kVyaw);
  const double tp = t.sp / t.cp;
  const double sec2 = 1.0 / (t.cp * t.cp);

  // d(R s)/d(angle) for R = Rz(yaw) Ry(pitch) Rx(roll), from the derivative
  // of a rotation about axis e being that rotation times [e]x:
  //  roll:  R (e_x x s), R's columns 1 and 2 weighted by -s_z and s_y;
  //  pitch: Rz (e_y x u) with u = Ry Rx s = Rz' R s;
  //  yaw:   e_z x (R s).
  // Cheaper than the three dR/dangle matrices times s, and it reuses R s.
  MotionJacobian j;
  j.pos_rpy.col(0) = r.col(2) * s(1) - r.col(1) * s(2);
  const double ux = t.cy * step(0) + t.sy * step(1);
  j.pos_rpy.col(1) << t.cy * step(2), t.sy * step(2), -ux;
  j.pos_rpy.col(2) << -step(1), step(0), 0.0;
  j.pos_vel = r * dt;

  j.rpy_rpy.setIdentity();
  j.rpy_rpy(0, 0) += (t.cr * tp * vp - t.sr * tp * vy) * dt;
  j.rpy_rpy(0, 1) = (t.sr * vp + t.cr * vy) * sec2 * dt;
  j.rpy_rpy(1, 0) = (-t.sr * vp - t.cr * vy) * dt;
  j.rpy_rpy(2, 0) = (t.cr * vp - t.sr * vy) / t.cp * dt;
  j.rpy_rpy(2, 1) = (t.sr * vp + t.cr * vy) * t.sp * sec2 * dt;

  j.rpy_rate << 1.0, t.sr * tp, t.cr * tp,
                0.0, t.cr,      -t.sr,
                0.0, t.sr / t.cp, t.cr / t.cp;
  j.rpy_rate *= dt;
  j.vel_acc = dt;
  return j;
}

}  // namespace

void motion_model_predict(StateVector& x, double dt) noexcept {
  const Trig t = trig_of(x);
  predict_with(t, body_to_world(t) * body_step(x, dt), x, dt);
}

MotionJacobian motion_model_jacobian(const StateVector& x, double dt) noexcept {
  const Trig t = trig_of(x);
  const Eigen::Matrix3d r = body_to_world(t);
  const Eigen::Vector3d s = body_step(x, dt);
  return jacobian_with(t, r, s, r * s, x, dt);
}

MotionJacobian motion_model_step(StateVector& x, double dt) noexcept {
  const Trig t = trig_of(x);
  const Eigen::Matrix3d r = body_to_world(t);
  const Eigen::Vector3d s = body_step(x, dt);
  const Eigen::Vector3d step = r * s;
  const MotionJacobian j = jacobian_with(t, r, s, step, x, dt);
  predict_with(t, step, x, dt);
  return j;
}

StateMatrix motion_model_jacobian_dense(const StateVector& x, double dt) noexcept {
  const MotionJacobian j = motion_model_jacobian(x, dt);
  StateMatrix f = StateMatrix::Identity();
  f.block<3, 3>(kX, kRoll) = j.pos_rpy;
  f.block<3, 3>(kX, kVx) = j.pos_vel;
  f.block<3, 3>(kX, kAx) = j.pos_vel * (0.5 * dt);
  f.block<3, 3>(kRoll, kRoll) = j.rpy_rpy;
  f.block<3, 3>(kRoll, kVroll) = j.rpy_rate;
  f.block<3, 3>(kVx, kAx) = Eigen::Matrix3d::Identity() * j.vel_acc;
  return f;
}

}  // namespace rtfuse::est
