#pragma once
// A decoded sensor message in the sensor's own frames, before any robot_localization
// preprocessing: what a transport decoder (LCM) or a driver hands to the loop.
// Trivially copyable so it travels through SPSC rings by value.
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/time.hpp"
#include "estimation/geodesy.hpp"
#include "estimation/state.hpp"

namespace rtfuse::est {

enum class SensorKind : std::uint8_t { kOdometry, kPose, kTwist, kImu, kNavSatFix };

struct PoseSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Matrix6 covariance = Matrix6::Zero();  // over x y z roll pitch yaw
};

struct TwistSample {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
  Matrix6 covariance = Matrix6::Zero();  // over vx vy vz vroll vpitch vyaw
};

struct ImuSample {
  bool has_orientation = false;  // sensor_msgs/Imu: covariance[0] == -1 means absent
  bool has_angular_velocity = false;
  bool has_linear_acceleration = false;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Matrix3 orientation_covariance = Matrix3::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  Matrix3 angular_velocity_covariance = Matrix3::Zero();
  Eigen::Vector3d linear_acceleration = Eigen::Vector3d::Zero();
  Matrix3 linear_acceleration_covariance = Matrix3::Zero();
};

// sensor_msgs/NavSatFix, keeping its status and covariance-type values.
struct NavSatFixSample {
  std::int8_t status = -1;           // NavSatStatus: -1 no fix, 0 fix, 1 SBAS, 2 GBAS
  std::uint8_t covariance_type = 0;  // 0 unknown, 1 approximated, 2 diagonal known, 3 known
  GeodeticPosition position;         // of the antenna
  Matrix3 covariance = Matrix3::Zero();  // east north up, m²
};

// Frame ids are resolved to indices of the runtime's FrameTree by the decoder
// (string compares happen off the real-time path); -1 means "not known".
struct SensorSample {
  TimeNs stamp = 0;            // header stamp, CLOCK_MONOTONIC-compatible ns
  std::uint8_t sensor = 0;     // index into the configured sensors
  SensorKind kind = SensorKind::kOdometry;
  std::int16_t frame = -1;       // header.frame_id
  std::int16_t child_frame = -1; // odometry child_frame_id
  PoseSample pose;    // kOdometry, kPose
  TwistSample twist;  // kOdometry, kTwist
  ImuSample imu;      // kImu
  NavSatFixSample navsat;  // kNavSatFix
};

}  // namespace rtfuse::est
