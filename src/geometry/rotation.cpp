// Euler conversions written out as tf2 does them (not via Eigen's eulerAngles,
// whose ranges and singular branch differ), so that angles read from a config
// or a log round-trip exactly as they would through tf2 in robot_localization.
#include "geometry/rotation.hpp"

#include <cmath>

#include "geometry/angles.hpp"

namespace rtfuse::geometry {

Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw) noexcept {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  // Rz(yaw) * Ry(pitch) * Rx(roll), expanded and grouped as tf2 groups it.
  const double cc = cr * cy, cs = cr * sy, sc = sr * cy, ss = sr * sy;
  Eigen::Matrix3d r;
  r << cp * cy, sp * sc - cs, sp * cc + ss,  //
      cp * sy, sp * ss + cc, sp * cs - sc,   //
      -sp, cp * sr, cp * cr;
  return r;
}

Eigen::Quaterniond quaternion_from_rpy(double roll, double pitch, double yaw) noexcept {
  const double cr = std::cos(0.5 * roll), sr = std::sin(0.5 * roll);
  const double cp = std::cos(0.5 * pitch), sp = std::sin(0.5 * pitch);
  const double cy = std::cos(0.5 * yaw), sy = std::sin(0.5 * yaw);
  // Eigen's constructor order is (w, x, y, z).
  return Eigen::Quaterniond(cr * cp * cy + sr * sp * sy,   //
                            sr * cp * cy - cr * sp * sy,   //
                            cr * sp * cy + sr * cp * sy,   //
                            cr * cp * sy - sr * sp * cy);
}

Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& r) noexcept {
  double roll, pitch, yaw;
  // tf2 enters its singular branch only when |r(2,0)| reaches 1 exactly (or
  // overshoots by rounding); it then sets yaw to 0 and puts everything in roll.
  if (std::abs(r(2, 0)) >= 1.0) {
    yaw = 0.0;
    pitch = r(2, 0) < 0.0 ? 0.5 * kPi : -0.5 * kPi;
    roll = std::atan2(r(2, 1), r(2, 2));
  } else {
    // tf2's first solution: pitch in (-pi/2, pi/2), so cos(pitch) > 0. The
    // divisions by it do not change the atan2 results but are kept so that
    // rounding matches tf2 bit for bit where it can.
    pitch = -std::asin(r(2, 0));
    const double cp = std::cos(pitch);
    roll = std::atan2(r(2, 1) / cp, r(2, 2) / cp);
    yaw = std::atan2(r(1, 0) / cp, r(0, 0) / cp);
  }
  return {roll, pitch, yaw};
}

Eigen::Vector3d rpy_from_quaternion(const Eigen::Quaterniond& q) noexcept {
  // tf2::Matrix3x3(q) scales by 2/|q|^2, so non-unit quaternions are accepted
  // as tf2 accepts them; Eigen's toRotationMatrix() assumes |q| = 1.
  const double d = q.squaredNorm();
  const double s = 2.0 / d;
  const double xs = q.x() * s, ys = q.y() * s, zs = q.z() * s;
  const double wx = q.w() * xs, wy = q.w() * ys, wz = q.w() * zs;
  const double xx = q.x() * xs, xy = q.x() * ys, xz = q.x() * zs;
  const double yy = q.y() * ys, yz = q.y() * zs, zz = q.z() * zs;
  Eigen::Matrix3d r;
  r << 1.0 - (yy + zz), xy - wz, xz + wy,  //
      xy + wz, 1.0 - (xx + zz), yz - wx,   //
      xz - wy, yz + wx, 1.0 - (xx + yy);
  return rpy_from_rotation(r);
}

}  // namespace rtfuse::geometry
