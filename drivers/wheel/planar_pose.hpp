#pragma once
// Dead-reckoned pose in the odometry plane, advanced by exact arc steps.
namespace rtfuse::drivers {

struct PlanarPose {
  double x = 0.0;    // m
  double y = 0.0;    // m
  double yaw = 0.0;  // rad, (-pi, pi]
};

// The pose after driving `distance` along a circular arc that turns by
// `dyaw` (constant speed and yaw rate over the step, which is what two
// encoder samples tell). Exact for any dyaw; a straight line when dyaw = 0.
PlanarPose integrate_arc(const PlanarPose& pose, double distance, double dyaw) noexcept;

// Angle in (-pi, pi].
double wrap_angle(double a) noexcept;

}  // namespace rtfuse::drivers
