#include "vision/egomotion_twist.hpp"

#include <cmath>

namespace rtfuse::vision {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d hat(const Eigen::Vector3d& w) noexcept {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

}  // namespace

Vec6 egomotion_log(const Vec6& params) noexcept {
  const Eigen::Matrix4d t = egomotion_transform(params);
  // The camera's pose in the previous camera's frame is the inverse of the
  // point transform.
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>().transpose();
  const Eigen::Vector3d p = -(r * t.topRightCorner<3, 1>());
  // Rotation logarithm without acos (whose glibc rounding is not checked
  // equal across architectures): sin from the skew part, cos from the trace.
  const Eigen::Vector3d s(0.5 * (r(2, 1) - r(1, 2)), 0.5 * (r(0, 2) - r(2, 0)), 0.5 * (r(1, 0) - r(0, 1)));
  const double sin_theta = std::sqrt(s.squaredNorm());
  const double cos_theta = 0.5 * (r.trace() - 1.0);
  const double theta = std::atan2(sin_theta, cos_theta);
  // theta / sin(theta), by its series where the division loses digits.
  const double scale = sin_theta > 1e-6 ? theta / sin_theta : 1.0 + theta * theta / 6.0;
  const Eigen::Vector3d phi = scale * s;
  // V^-1 = I - phi^/2 + c phi^2, c = (1 - (theta/2) cot(theta/2)) / theta^2.
  const double c = theta > 1e-4 ? (1.0 - 0.5 * theta * std::sin(theta) / (1.0 - std::cos(theta))) / (theta * theta)
                                 : 1.0 / 12.0 + theta * theta / 720.0;
  const Eigen::Matrix3d w = hat(phi);
  const Eigen::Vector3d rho = p - 0.5 * (w * p) + c * (w * (w * p));
  Vec6 out;
  out << phi, rho;
  return out;
}

CameraTwist egomotion_twist(const Egomotion& motion, double dt_s) noexcept {
  CameraTwist out;
  if (!motion.ok || !(dt_s > 0.0) || !motion.params.allFinite() || !motion.covariance.allFinite()) return out;
  // More than a quarter turn between two frames is no camera motion; the
  // logarithm's series would also lose its meaning near a half turn.
  if (motion.params.head<3>().squaredNorm() > 0.25 * M_PI * M_PI) return out;
  const Vec6 xi = egomotion_log(motion.params);
  // d xi / d params by central differences.
  Mat6 j;
  for (int k = 0; k < 6; ++k) {
    constexpr double h = 1e-6;
    Vec6 plus = motion.params, minus = motion.params;
    plus(k) += h;
    minus(k) -= h;
    j.col(k) = (egomotion_log(plus) - egomotion_log(minus)) / (2.0 * h);
  }
  const Mat6 c_xi = j * motion.covariance * j.transpose();
  // Reorder to linear-then-angular and divide by dt.
  Eigen::Matrix<double, 6, 6> perm = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 3; ++i) {
    perm(i, 3 + i) = 1.0;
    perm(3 + i, i) = 1.0;
  }
  const double inv_dt = 1.0 / dt_s;
  out.angular = xi.head<3>() * inv_dt;
  out.linear = xi.tail<3>() * inv_dt;
  out.covariance = (perm * c_xi * perm.transpose()) * (inv_dt * inv_dt);
  // Symmetric to the last bit: the filter checks covariances it is given.
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  out.ok = out.linear.allFinite() && out.angular.allFinite() && out.covariance.allFinite();
  return out;
}

}  // namespace rtfuse::vision
