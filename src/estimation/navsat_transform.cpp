#include "estimation/navsat_transform.hpp"

#include <cmath>

#include "geometry/angles.hpp"
#include "geometry/rotation.hpp"

namespace rtfuse::est {
namespace {

bool finite_positive(double v) noexcept { return std::isfinite(v) && v > 0.0; }

Eigen::Quaterniond yaw_rotation(double yaw) noexcept { return geometry::quaternion_from_rpy(0.0, 0.0, yaw); }

double yaw_of(const Eigen::Quaterniond& q) noexcept { return geometry::rpy_from_quaternion(q).z(); }

}  // namespace

const char* validate(const NavsatParams& p) noexcept {
  if (!std::isfinite(p.magnetic_declination_rad) || std::fabs(p.magnetic_declination_rad) > 3.2)
    return "magnetic_declination_radians must be finite, within ±π";
  if (!std::isfinite(p.yaw_offset_rad) || std::fabs(p.yaw_offset_rad) > 6.3)
    return "yaw_offset must be finite, within ±2π (radians)";
  if (p.manual_datum && !is_valid_geodetic(p.datum))
    return "datum must be a valid latitude (±90°) and longitude (±180°) in degrees";
  if (p.manual_datum && (!std::isfinite(p.datum_yaw_rad) || std::fabs(p.datum_yaw_rad) > 6.3))
    return "datum yaw must be finite, within ±2π (radians)";
  if (!finite_positive(p.unknown_horizontal_variance) || !finite_positive(p.unknown_vertical_variance))
    return "the variances for an unknown covariance type must be finite and > 0 (m²)";
  if (!finite_positive(p.max_jump_m)) return "max_jump must be finite and > 0 (m)";
  if (!std::isfinite(p.max_speed_mps) || p.max_speed_mps < 0.0) return "max_speed must be finite and >= 0 (m/s)";
  if (!p.base_p_antenna.allFinite() || p.base_p_antenna.norm() > 100.0)
    return "the antenna's lever arm must be finite and under 100 m";
  return "";
}

const char* to_string(NavsatRejection r) noexcept {
  switch (r) {
    case NavsatRejection::kNone: return "none";
    case NavsatRejection::kNoFix: return "no_fix";
    case NavsatRejection::kInvalidPosition: return "invalid_position";
    case NavsatRejection::kInvalidCovariance: return "invalid_covariance";
    case NavsatRejection::kNoHeading: return "no_heading";
    case NavsatRejection::kJump: return "jump";
  }
  return "unknown";
}

NavsatTransform::NavsatTransform(const NavsatParams& params) noexcept : params_(params) { reset(); }

void NavsatTransform::reset() noexcept {
  has_last_ = false;
  outlier_run_ = 0;
  has_transform_ = false;
  if (!params_.manual_datum) return;
  // The node's datum service: the robot stands at the datum, at the world
  // origin, heading the datum's (corrected) yaw; no lever arm is taken off.
  GeodeticPosition datum = params_.datum;
  plane_.reset(datum);
  const double heading = params_.datum_yaw_rad + params_.magnetic_declination_rad + params_.yaw_offset_rad;
  geometry::RigidTransform enu_T_base;
  enu_T_base.rotation = yaw_rotation(heading);
  world_T_enu_ = enu_T_base.inverse();
  has_transform_ = true;
}

void NavsatTransform::set_heading(const Eigen::Quaterniond& orientation) noexcept {
  if (!orientation.coeffs().allFinite() || orientation.norm() < 0.5) return;
  const Eigen::Vector3d rpy = geometry::rpy_from_quaternion(orientation.normalized());
  const double yaw = geometry::wrap_angle(rpy.z() + params_.magnetic_declination_rad + params_.yaw_offset_rad);
  heading_ = geometry::quaternion_from_rpy(rpy.x(), rpy.y(), yaw);
  has_heading_ = true;
}

NavsatRejection NavsatTransform::covariance_of(const NavSatFixSample& fix, Matrix3* enu) const noexcept {
  const Matrix3& c = fix.covariance;
  switch (fix.covariance_type) {
    case 0:  // unknown: the configured default
      *enu = Matrix3::Zero();
      (*enu)(0, 0) = (*enu)(1, 1) = params_.unknown_horizontal_variance;
      (*enu)(2, 2) = params_.unknown_vertical_variance;
      return NavsatRejection::kNone;
    case 1:  // approximated
    case 2:  // diagonal known
      if (!finite_positive(c(0, 0)) || !finite_positive(c(1, 1)) || !finite_positive(c(2, 2)))
        return NavsatRejection::kInvalidCovariance;
      *enu = c.diagonal().asDiagonal();
      return NavsatRejection::kNone;
    case 3: {  // known
      if (!c.allFinite()) return NavsatRejection::kInvalidCovariance;
      const Matrix3 s = 0.5 * (c + c.transpose());
      for (int i = 0; i < 3; ++i) {
        if (!(s(i, i) > 0.0)) return NavsatRejection::kInvalidCovariance;
        for (int j = 0; j < i; ++j) {
          // A correlation beyond ±1 is no covariance.
          if (s(i, j) * s(i, j) > s(i, i) * s(j, j)) return NavsatRejection::kInvalidCovariance;
        }
      }
      *enu = s;
      return NavsatRejection::kNone;
    }
    default: return NavsatRejection::kInvalidCovariance;
  }
}

void NavsatTransform::anchor(const Eigen::Vector3d& antenna_enu, const geometry::RigidTransform& world_T_base) noexcept {
  // base_link in ENU at the datum, from the antenna and the IMU's attitude.
  geometry::RigidTransform enu_T_base;
  enu_T_base.translation = antenna_enu - heading_ * params_.base_p_antenna;
  enu_T_base.rotation = yaw_rotation(yaw_of(heading_));
  // The filter's pose then, kept level (see the header).
  geometry::RigidTransform world_T_base_level;
  world_T_base_level.translation = world_T_base.translation;
  world_T_base_level.rotation = yaw_rotation(yaw_of(world_T_base.rotation));
  world_T_enu_ = world_T_base_level * enu_T_base.inverse();
  has_transform_ = true;
}

bool NavsatTransform::passes_jump_gate(TimeNs stamp, const Eigen::Vector3d& enu) noexcept {
  const auto within = [this](const Eigen::Vector3d& a, TimeNs a_stamp, const Eigen::Vector3d& b, TimeNs b_stamp) {
    const double dt = std::fabs(static_cast<double>(b_stamp - a_stamp)) * 1e-9;
    return (b - a).head<2>().norm() <= params_.max_jump_m + params_.max_speed_mps * dt;
  };
  if (!has_last_ || within(last_enu_, last_stamp_, enu, stamp)) {
    outlier_run_ = 0;
  } else {
    const bool continues_run = outlier_run_ > 0 && within(outlier_enu_, outlier_stamp_, enu, stamp);
    outlier_run_ = continues_run ? outlier_run_ + 1 : 1;
    outlier_enu_ = enu;
    outlier_stamp_ = stamp;
    if (outlier_run_ < kReanchorFixes) return false;
    ++stats_.reanchors;
    outlier_run_ = 0;
  }
  has_last_ = true;
  last_enu_ = enu;
  last_stamp_ = stamp;
  return true;
}

NavsatRejection NavsatTransform::convert(TimeNs stamp, const NavSatFixSample& fix,
                                         const geometry::RigidTransform& world_T_base, PoseSample* out) noexcept {
  last_ = judge(stamp, fix, world_T_base, out);
  return last_;
}

NavsatRejection NavsatTransform::judge(TimeNs stamp, const NavSatFixSample& fix,
                                       const geometry::RigidTransform& world_T_base, PoseSample* out) noexcept {
  if (fix.status < 0) {
    ++stats_.no_fix;
    return NavsatRejection::kNoFix;
  }
  if (!is_valid_geodetic(fix.position)) {
    ++stats_.invalid_position;
    return NavsatRejection::kInvalidPosition;
  }
  Matrix3 enu_covariance;
  if (covariance_of(fix, &enu_covariance) != NavsatRejection::kNone) {
    ++stats_.invalid_covariance;
    return NavsatRejection::kInvalidCovariance;
  }
  if (!has_transform_) {
    if (!has_heading_) {
      ++stats_.waiting_for_heading;
      return NavsatRejection::kNoHeading;
    }
    plane_.reset(fix.position);
    anchor(Eigen::Vector3d::Zero(), world_T_base);
  }
  const Eigen::Vector3d enu = plane_.forward(fix.position);
  if (!passes_jump_gate(stamp, enu)) {
    ++stats_.jumps;
    return NavsatRejection::kJump;
  }
  const Eigen::Vector3d world_p_antenna = world_T_enu_ * enu;
  const Eigen::Matrix3d world_R_enu = world_T_enu_.rotation_matrix();
  out->position = world_p_antenna - world_T_base.rotation * params_.base_p_antenna;
  if (params_.zero_altitude) out->position.z() = 0.0;
  out->orientation = Eigen::Quaterniond::Identity();
  out->covariance.setZero();
  out->covariance.topLeftCorner<3, 3>() = world_R_enu * enu_covariance * world_R_enu.transpose();
  ++stats_.accepted;
  return NavsatRejection::kNone;
}

NavSatFixSample NavsatTransform::filtered_fix(const Eigen::Vector3d& world_p_base,
                                              const Matrix3& world_covariance) const noexcept {
  const geometry::RigidTransform enu_T_world = world_T_enu_.inverse();
  const Eigen::Matrix3d enu_R_world = enu_T_world.rotation_matrix();
  NavSatFixSample f;
  f.status = 2;  // the node's STATUS_GBAS_FIX
  f.covariance_type = 3;
  f.position = plane_.reverse(enu_T_world * world_p_base);
  f.covariance = enu_R_world * world_covariance * enu_R_world.transpose();
  return f;
}

}  // namespace rtfuse::est
