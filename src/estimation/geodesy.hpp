#pragma once
// WGS-84 geodetic coordinates and the local tangent plane (east, north, up)
// at a datum: what the navsat transform needs to put a GNSS fix in metres.
//
// Written here rather than taken from GeographicLib (which is what
// robot_localization uses, and what tests/reference checks this against)
// because the loop's arithmetic must give the same bits on the board and on
// the laptop that replays its recording. Debian's arm64 libGeographicLib is
// built with GCC's aarch64 default of FMA contraction: its
// LocalCartesian::IntForward, Geocentric::IntForward and
// TransverseMercator::Forward contain fused multiply-adds (aarch64 objdump of
// libgeographiclib23 2.1.2: 6, 2 and 15 fmadd/fmsub), so a fix would project
// to different last bits on the two machines. This file is compiled with the
// project's -ffp-contract=off and uses only glibc functions checked equal on
// both (sin, cos, atan2, sqrt: docs/design.md).
#include <Eigen/Core>

namespace rtfuse::est {

struct GeodeticPosition {
  double latitude_deg = 0.0;   // WGS-84, north positive
  double longitude_deg = 0.0;  // east positive
  double altitude_m = 0.0;     // above the ellipsoid
};

// Finite, latitude within ±90°, longitude within ±180°, altitude between
// -12 km and 100 km (below the deepest trench, above which no receiver on a
// robot reports): a fix outside is a corrupt or absurd reading.
bool is_valid_geodetic(const GeodeticPosition& p) noexcept;

// Earth-centred, earth-fixed metres of a geodetic position (valid input).
Eigen::Vector3d geodetic_to_ecef(const GeodeticPosition& p) noexcept;
// Back, with a fixed number of Bowring iterations (bounded work): under a
// micrometre for altitudes within is_valid_geodetic's range.
GeodeticPosition ecef_to_geodetic(const Eigen::Vector3d& ecef) noexcept;

// The east-north-up plane tangent to the ellipsoid at a datum. Exact (no
// flat-earth approximation): a point projects through ECEF, so distances
// and directions stay right kilometres from the datum, as GeographicLib's
// LocalCartesian does.
class LocalTangentPlane {
 public:
  LocalTangentPlane() { reset(GeodeticPosition{}); }
  // datum must satisfy is_valid_geodetic.
  void reset(const GeodeticPosition& datum) noexcept;

  Eigen::Vector3d forward(const GeodeticPosition& p) const noexcept;  // ENU metres
  GeodeticPosition reverse(const Eigen::Vector3d& enu) const noexcept;
  const GeodeticPosition& datum() const noexcept { return datum_; }

 private:
  GeodeticPosition datum_;
  Eigen::Vector3d datum_ecef_;
  Eigen::Matrix3d ecef_R_enu_;  // columns: east, north, up in ECEF
};

}  // namespace rtfuse::est
