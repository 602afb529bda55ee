#include "drivers/wheel/planar_pose.hpp"
#include "core/physical_constants.hpp"

#include <cmath>

namespace rtfuse::drivers {

namespace {

// sin(a)/a without the 0/0: the series is exact to double precision below 1e-4.
double sinc(double a) {
  return std::fabs(a) < 1e-4 ? 1.0 - a * a / 6.0 : std::sin(a) / a;
}
}  // namespace

double wrap_angle(double a) noexcept {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

PlanarPose integrate_arc(const PlanarPose& pose, double distance, double dyaw) noexcept {
  // The chord of the arc points along the mean heading; its length is
  // distance * sin(dyaw/2) / (dyaw/2).
  const double chord = distance * sinc(0.5 * dyaw);
  const double heading = pose.yaw + 0.5 * dyaw;
  PlanarPose out;
  out.x = pose.x + chord * std::cos(heading);
  out.y = pose.y + chord * std::sin(heading);
  out.yaw = wrap_angle(pose.yaw + dyaw);
  return out;
}

}  // namespace rtfuse::drivers
