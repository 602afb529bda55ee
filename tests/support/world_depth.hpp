#pragma once
// What the simulator's camera truly sees: the depth along the left eye's
// optical axis of the nearest surface of the world through a pixel of an
// ideal pinhole eye (tests/support/pinhole_stereo.hpp), by casting the ray
// against every surface of the CameraWorld. The truth the depth and map
// tests score against.
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "geometry/rigid_transform.hpp"
#include "sim/camera_world.hpp"

namespace rtfuse::test {

// The depth Z (metres along the optical axis) of what pixel (u, v) sees,
// the eye with focal length f and principal point (cx, cy) at world_T_left;
// +inf when the ray meets nothing. Surfaces seen from behind are invisible.
inline double true_depth(const sim::CameraWorld& world, const geometry::RigidTransform& world_T_left, double f,
                         double cx, double cy, double u, double v) {
  const Eigen::Matrix3d r = world_T_left.rotation.toRotationMatrix();
  const Eigen::Vector3d dir = r * Eigen::Vector3d((u - cx) / f, (v - cy) / f, 1.0);  // optical z = 1
  const Eigen::Vector3d& o = world_T_left.translation;
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < world.surface_count(); ++i) {
    const sim::WorldSurface& s = world.surface(i);
    const double facing = s.normal.dot(dir);
    if (facing >= 0.0) continue;
    const double t = s.normal.dot(s.origin - o) / facing;
    if (t <= 0.0 || t >= nearest) continue;
    const Eigen::Vector3d p = o + t * dir - s.origin;
    const double a = p.dot(s.axis_u), b = p.dot(s.axis_v);
    if (a < 0.0 || a > s.size_u || b < 0.0 || b > s.size_v) continue;
    nearest = t;  // the depth along the optical axis, since the ray's z is 1
  }
  return nearest;
}

}  // namespace rtfuse::test
