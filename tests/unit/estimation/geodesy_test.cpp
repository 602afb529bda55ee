// WGS-84 geodesy: known points, round trips, and the tangent plane's
// geometry. tests/reference checks the same functions against GeographicLib.
#include "estimation/geodesy.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace rtfuse::est {
namespace geodesy_test {

constexpr double kA = 6378137.0;
constexpr double kB = 6356752.314245179;  // WGS-84 semi-minor axis

TEST(Geodesy, EquatorAndPolesLandOnTheAxes) {
  const Eigen::Vector3d e = geodetic_to_ecef({0.0, 0.0, 0.0});
  EXPECT_NEAR(e.x(), kA, 1e-9);
  EXPECT_NEAR(e.y(), 0.0, 1e-9);
  EXPECT_NEAR(e.z(), 0.0, 1e-9);
  const Eigen::Vector3d east = geodetic_to_ecef({0.0, 90.0, 100.0});
  EXPECT_NEAR(east.y(), kA + 100.0, 1e-8);
  EXPECT_NEAR(east.x(), 0.0, 1e-6);
  const Eigen::Vector3d north = geodetic_to_ecef({90.0, 0.0, 0.0});
  EXPECT_NEAR(north.z(), kB, 1e-6);
  EXPECT_NEAR(north.x(), 0.0, 1e-6);
  const Eigen::Vector3d south = geodetic_to_ecef({-90.0, 37.0, 10.0});
  EXPECT_NEAR(south.z(), -(kB + 10.0), 1e-6);
}

TEST(Geodesy, EcefRoundTripIsExactToAMicrometre) {
  for (double lat = -90.0; lat <= 90.0; lat += 7.5) {
    for (double lon = -180.0; lon <= 180.0; lon += 22.5) {
      for (double alt : {-11000.0, -50.0, 0.0, 250.0, 8848.0, 99000.0}) {
        const GeodeticPosition p{lat, lon, alt};
        const GeodeticPosition q = ecef_to_geodetic(geodetic_to_ecef(p));
        // A micrometre is 9e-12 degrees of latitude.
        EXPECT_NEAR(q.latitude_deg, lat, 1e-11) << lat << " " << lon << " " << alt;
        if (std::fabs(lat) < 90.0) {
          // Longitude is undefined at the poles; at ±180 both signs are the same meridian.
          const double dlon = std::remainder(q.longitude_deg - lon, 360.0);
          EXPECT_NEAR(dlon * std::cos(lat * M_PI / 180.0), 0.0, 1e-11) << lat << " " << lon;
        }
        EXPECT_NEAR(q.altitude_m, alt, 1e-6) << lat << " " << lon << " " << alt;
      }
    }
  }
}

TEST(Geodesy, ValidityRejectsAbsurdAndNonFinitePositions) {
  EXPECT_TRUE(is_valid_geodetic({48.1, 11.5, 520.0}));
  EXPECT_TRUE(is_valid_geodetic({-90.0, 180.0, 0.0}));
  EXPECT_FALSE(is_valid_geodetic({90.0001, 0.0, 0.0}));
  EXPECT_FALSE(is_valid_geodetic({0.0, -180.5, 0.0}));
  EXPECT_FALSE(is_valid_geodetic({NAN, 0.0, 0.0}));
  EXPECT_FALSE(is_valid_geodetic({0.0, INFINITY, 0.0}));
  EXPECT_FALSE(is_valid_geodetic({0.0, 0.0, NAN}));
  EXPECT_FALSE(is_valid_geodetic({0.0, 0.0, 150000.0}));
  EXPECT_FALSE(is_valid_geodetic({0.0, 0.0, -20000.0}));
}

TEST(LocalTangentPlane, AxesPointEastNorthUp) {
  LocalTangentPlane plane;
  const GeodeticPosition datum{48.137, 11.575, 519.0};
  plane.reset(datum);
  EXPECT_LT(plane.forward(datum).norm(), 1e-9);
  // One arc-second north is about 30.9 m at this latitude (meridian radius).
  const Eigen::Vector3d n = plane.forward({datum.latitude_deg + 1.0 / 3600.0, datum.longitude_deg, datum.altitude_m});
  EXPECT_NEAR(n.x(), 0.0, 1e-6);
  EXPECT_NEAR(n.y(), 30.89, 0.02);
  EXPECT_LT(n.z(), 0.0);  // the ellipsoid falls away below the plane
  EXPECT_GT(n.z(), -1e-3);
  const Eigen::Vector3d e = plane.forward({datum.latitude_deg, datum.longitude_deg + 1.0 / 3600.0, datum.altitude_m});
  // ... and one east is the parallel's radius, (N + h) cos(lat), times an arc-second (chord and arc differ by nanometres).
  const double slat = std::sin(datum.latitude_deg * M_PI / 180.0);
  const double n_radius = kA / std::sqrt(1.0 - 0.00669437999014 * slat * slat);
  EXPECT_NEAR(e.x(), (n_radius + datum.altitude_m) * std::cos(datum.latitude_deg * M_PI / 180.0) * M_PI / 648000.0, 1e-4);
  EXPECT_NEAR(e.y(), 0.0, 1e-3);  // the parallel curves north of the plane's x axis by millimetres
  const Eigen::Vector3d u = plane.forward({datum.latitude_deg, datum.longitude_deg, datum.altitude_m + 12.5});
  EXPECT_NEAR(u.x(), 0.0, 1e-9);
  EXPECT_NEAR(u.y(), 0.0, 1e-9);
  EXPECT_NEAR(u.z(), 12.5, 1e-9);
}

TEST(LocalTangentPlane, ReverseUndoesForwardKilometresAway) {
  LocalTangentPlane plane;
  for (const GeodeticPosition& datum :
       {GeodeticPosition{48.137, 11.575, 519.0}, GeodeticPosition{-33.86, 151.21, 3.0},
        GeodeticPosition{78.22, 15.65, 10.0}, GeodeticPosition{0.0, 179.999, 0.0}}) {
    plane.reset(datum);
    for (const Eigen::Vector3d& enu : {Eigen::Vector3d(0.1, -0.2, 0.0), Eigen::Vector3d(1234.5, -987.6, 12.0),
                                       Eigen::Vector3d(-25000.0, 40000.0, -120.0)}) {
      const Eigen::Vector3d back = plane.forward(plane.reverse(enu));
      EXPECT_LT((back - enu).norm(), 1e-6) << datum.latitude_deg << " " << enu.transpose();
    }
  }
}

}  // namespace geodesy_test
}  // namespace rtfuse::est
