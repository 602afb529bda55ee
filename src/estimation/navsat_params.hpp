#pragma once
// What a navsat sensor is configured with: robot_localization's
// navsat_transform_node parameters, plus the jump gate and the antenna's
// lever arm. The transform itself: estimation/navsat_transform.hpp.
#include <Eigen/Core>

#include "estimation/geodesy.hpp"

namespace rtfuse::est {

struct NavsatParams {
  double magnetic_declination_rad = 0.0;
  double yaw_offset_rad = 0.0;
  bool zero_altitude = false;
  // wait_for_datum: the datum is this position and heading (in the IMU's
  // convention, corrected like the IMU's), not the first fix; the world
  // frame's origin is the datum and the robot is taken to stand there.
  bool manual_datum = false;
  GeodeticPosition datum;
  double datum_yaw_rad = 0.0;
  // Variances for a fix whose covariance type is unknown (m²).
  double unknown_horizontal_variance = 4.0;
  double unknown_vertical_variance = 16.0;
  // A fix farther from the last accepted one than max_jump_m plus
  // max_speed_mps times the time between them is a multipath jump or a
  // corrupt position: rejected and counted. NavsatTransform::kReanchorFixes
  // such fixes in a row that agree with each other are taken as the truth (the last accepted
  // one was the outlier).
  double max_jump_m = 25.0;
  double max_speed_mps = 5.0;
  // use_odometry_yaw: the datum's heading is the filter's own yaw (when an
  // absolute yaw source feeds it) instead of an IMU's.
  bool use_filter_yaw = false;
  // The antenna in base_link (the frame tree's base_link -> antenna frame).
  Eigen::Vector3d base_p_antenna = Eigen::Vector3d::Zero();
};

// "" when usable, else the reason naming the key (the config loader adds
// the file).
const char* validate(const NavsatParams& p) noexcept;

}  // namespace rtfuse::est
