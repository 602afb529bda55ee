#include "estimation/geodesy.hpp"

#include <cmath>

namespace rtfuse::est {
namespace {

// WGS-84 (NIMA TR8350.2).
constexpr double kA = 6378137.0;
constexpr double kF = 1.0 / 298.257223563;
constexpr double kB = kA * (1.0 - kF);
constexpr double kE2 = kF * (2.0 - kF);            // first eccentricity squared
constexpr double kEp2 = kE2 / (1.0 - kE2);         // second eccentricity squared
constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;
// Three iterations from the reduced-latitude guess reach the double's
// resolution for any point within 100 km of the surface.
constexpr int kBowringIterations = 3;

}  // namespace

bool is_valid_geodetic(const GeodeticPosition& p) noexcept {
  return std::isfinite(p.latitude_deg) && std::isfinite(p.longitude_deg) && std::isfinite(p.altitude_m) &&
         std::fabs(p.latitude_deg) <= 90.0 && std::fabs(p.longitude_deg) <= 180.0 && p.altitude_m >= -12000.0 &&
         p.altitude_m <= 100000.0;
}

Eigen::Vector3d geodetic_to_ecef(const GeodeticPosition& p) noexcept {
  const double lat = p.latitude_deg * kDegToRad;
  const double lon = p.longitude_deg * kDegToRad;
  const double slat = std::sin(lat);
  const double clat = std::cos(lat);
  const double n = kA / std::sqrt(1.0 - kE2 * slat * slat);  // prime vertical radius
  const double r = (n + p.altitude_m) * clat;
  return {r * std::cos(lon), r * std::sin(lon), (n * (1.0 - kE2) + p.altitude_m) * slat};
}

GeodeticPosition ecef_to_geodetic(const Eigen::Vector3d& ecef) noexcept {
  const double x = ecef.x();
  const double y = ecef.y();
  const double z = ecef.z();
  // Not std::hypot: glibc's rounds differently on x86-64 and aarch64.
  const double p = std::sqrt(x * x + y * y);
  double beta = std::atan2(z, (1.0 - kF) * p);
  double lat = beta;
  for (int i = 0; i < kBowringIterations; ++i) {
    const double sb = std::sin(beta);
    const double cb = std::cos(beta);
    lat = std::atan2(z + kEp2 * kB * sb * sb * sb, p - kE2 * kA * cb * cb * cb);
    beta = std::atan2((1.0 - kF) * std::sin(lat), std::cos(lat));
  }
  const double slat = std::sin(lat);
  GeodeticPosition g;
  g.latitude_deg = lat * kRadToDeg;
  g.longitude_deg = std::atan2(y, x) * kRadToDeg;
  // This form of the height holds at the poles too (p = 0, cos(lat) = 0).
  g.altitude_m = p * std::cos(lat) + z * slat - kA * std::sqrt(1.0 - kE2 * slat * slat);
  return g;
}

void LocalTangentPlane::reset(const GeodeticPosition& datum) noexcept {
  datum_ = datum;
  datum_ecef_ = geodetic_to_ecef(datum);
  const double lat = datum.latitude_deg * kDegToRad;
  const double lon = datum.longitude_deg * kDegToRad;
  const double sp = std::sin(lat);
  const double cp = std::cos(lat);
  const double sl = std::sin(lon);
  const double cl = std::cos(lon);
  ecef_R_enu_ << -sl, -sp * cl, cp * cl,  //
      cl, -sp * sl, cp * sl,              //
      0.0, cp, sp;
}

Eigen::Vector3d LocalTangentPlane::forward(const GeodeticPosition& p) const noexcept {
  return ecef_R_enu_.transpose() * (geodetic_to_ecef(p) - datum_ecef_);
}

GeodeticPosition LocalTangentPlane::reverse(const Eigen::Vector3d& enu) const noexcept {
  return ecef_to_geodetic(datum_ecef_ + ecef_R_enu_ * enu);
}

}  // namespace rtfuse::est
