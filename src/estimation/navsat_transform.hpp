#pragma once
// robot_localization's navsat_transform_node as a pure function of its
// inputs: a GNSS fix (latitude, longitude, altitude) becomes a position of
// base_link in the filter's world frame (map), fused like any pose source.
//
// The transform world <- ENU is fixed once, at the datum: the first good fix
// (or a configured latitude, longitude and heading), the IMU's heading then
// (corrected by magnetic_declination_radians and yaw_offset: the IMU is
// expected to read 0 facing east), and the filter's pose then. Every later
// fix goes through the same transform, and the antenna's lever arm is taken
// off with the robot's orientation at the fix's epoch.
//
// Two differences from the node, both deliberate:
// - the datum anchors only the world pose's yaw and position: the node keeps
//   its roll and pitch too, which tilts the whole map when the robot stood on
//   a slope at the first fix, although map and ENU are both level;
// - the plane is the local tangent plane at the datum (the node's
//   use_local_cartesian) rather than the UTM grid: no grid convergence
//   between the IMU's true north and the map's y axis, no scale error.
//
// Fixed size, no allocation, no exceptions: the loop calls it.
#include <cstdint>

#include "core/time.hpp"
#include "estimation/geodesy.hpp"
#include "estimation/navsat_params.hpp"
#include "estimation/sensor_sample.hpp"
#include "geometry/rigid_transform.hpp"

namespace rtfuse::est {

enum class NavsatRejection : std::uint8_t {
  kNone,
  kNoFix,              // status -1
  kInvalidPosition,    // NaN or outside is_valid_geodetic
  kInvalidCovariance,  // not finite, not positive, not a covariance, or an unknown type value
  kNoHeading,          // no datum yet and no heading to anchor it with
  kJump,               // beyond the jump gate
};
const char* to_string(NavsatRejection r) noexcept;

struct NavsatStats {
  std::int64_t accepted = 0;
  std::int64_t no_fix = 0;
  std::int64_t invalid_position = 0;
  std::int64_t invalid_covariance = 0;
  std::int64_t waiting_for_heading = 0;
  std::int64_t jumps = 0;
  std::int64_t reanchors = 0;  // jump-gate outliers that turned out to be the truth
};

class NavsatTransform {
 public:
  static constexpr int kReanchorFixes = 3;

  NavsatTransform() : NavsatTransform(NavsatParams{}) {}
  // params must pass validate().
  explicit NavsatTransform(const NavsatParams& params) noexcept;

  // Forgets the datum (unless configured) and the jump gate's reference.
  void reset() noexcept;

  // The heading source: base_link's orientation as the IMU reports it
  // (mounting already removed). Only the datum uses it.
  void set_heading(const Eigen::Quaterniond& orientation) noexcept;
  bool has_heading() const noexcept { return has_heading_; }

  // One fix, stamped at its epoch. world_T_base: the filter's estimate at
  // that epoch; at the datum it anchors the transform, afterwards its
  // orientation takes off the lever arm. On kNone, *out holds base_link's
  // position in the world frame with the fix's covariance rotated into it
  // (orientation identity, unused).
  NavsatRejection convert(TimeNs stamp, const NavSatFixSample& fix, const geometry::RigidTransform& world_T_base,
                          PoseSample* out) noexcept;

  bool has_transform() const noexcept { return has_transform_; }
  // world <- ENU at the datum (valid once has_transform()).
  const geometry::RigidTransform& world_T_enu() const noexcept { return world_T_enu_; }
  const LocalTangentPlane& plane() const noexcept { return plane_; }

  // The node's filtered fix: a world position of base_link and its
  // covariance as latitude, longitude, altitude and an ENU covariance
  // (type known, status GBAS fix as the node reports it). Needs the transform.
  NavSatFixSample filtered_fix(const Eigen::Vector3d& world_p_base, const Matrix3& world_covariance) const noexcept;

  const NavsatStats& stats() const noexcept { return stats_; }
  // The verdict on the last fix (kNone before any).
  NavsatRejection last() const noexcept { return last_; }
  const NavsatParams& params() const noexcept { return params_; }

 private:
  NavsatRejection judge(TimeNs stamp, const NavSatFixSample& fix, const geometry::RigidTransform& world_T_base,
                        PoseSample* out) noexcept;
  NavsatRejection covariance_of(const NavSatFixSample& fix, Matrix3* enu) const noexcept;
  bool passes_jump_gate(TimeNs stamp, const Eigen::Vector3d& enu) noexcept;
  void anchor(const Eigen::Vector3d& antenna_enu, const geometry::RigidTransform& world_T_base) noexcept;

  NavsatParams params_;
  NavsatStats stats_;
  NavsatRejection last_ = NavsatRejection::kNone;
  LocalTangentPlane plane_;
  bool has_heading_ = false;
  Eigen::Quaterniond heading_ = Eigen::Quaterniond::Identity();  // IMU orientation, corrected yaw
  bool has_transform_ = false;
  geometry::RigidTransform world_T_enu_;
  // The jump gate: the last accepted antenna position, and the run of
  // rejected fixes that agree with each other.
  bool has_last_ = false;
  Eigen::Vector3d last_enu_ = Eigen::Vector3d::Zero();
  TimeNs last_stamp_ = 0;
  int outlier_run_ = 0;
  Eigen::Vector3d outlier_enu_ = Eigen::Vector3d::Zero();
  TimeNs outlier_stamp_ = 0;
};

}  // namespace rtfuse::est
