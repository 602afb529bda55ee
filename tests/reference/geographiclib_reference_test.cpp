// estimation/geodesy against GeographicLib, the library robot_localization
// projects with (Geocentric::WGS84(), LocalCartesian). Test-only: the
// runtime cannot link Debian's arm64 build of it (src/estimation/geodesy.hpp
// says why), so this is where the hand-written geodesy earns its trust.
#include <cmath>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <gtest/gtest.h>

#include "estimation/geodesy.hpp"

namespace rtfuse::est {
namespace {

const GeodeticPosition kDatums[] = {
    {52.5163, 13.3777, 34.0},    // Berlin
    {-33.8568, 151.2153, 5.0},   // Sydney
    {37.7749, -122.4194, 16.0},  // San Francisco
    {78.2232, 15.6469, 10.0},    // Svalbard
    {0.0001, 179.9999, 0.0},     // the antimeridian at the equator
    {-89.99, 0.0, 2800.0},       // the South Pole station
    {27.9881, 86.9250, 8848.0},  // Everest
};

TEST(GeographicLibReference, EcefAgreesEverywhere) {
  const GeographicLib::Geocentric& earth = GeographicLib::Geocentric::WGS84();
  double worst = 0.0;
  for (double lat = -90.0; lat <= 90.0; lat += 3.75) {
    for (double lon = -180.0; lon <= 180.0; lon += 11.25) {
      for (double alt : {-11000.0, 0.0, 1234.5, 99000.0}) {
        double x, y, z;
        earth.Forward(lat, lon, alt, x, y, z);
        const Eigen::Vector3d ours = geodetic_to_ecef({lat, lon, alt});
        worst = std::max(worst, (ours - Eigen::Vector3d(x, y, z)).norm());
        double rlat, rlon, ralt;
        earth.Reverse(x, y, z, rlat, rlon, ralt);
        const GeodeticPosition back = ecef_to_geodetic(Eigen::Vector3d(x, y, z));
        EXPECT_NEAR(back.latitude_deg, rlat, 1e-11) << lat << " " << lon << " " << alt;
        EXPECT_NEAR(back.altitude_m, ralt, 1e-6) << lat << " " << lon << " " << alt;
        if (std::fabs(lat) < 90.0) {
          EXPECT_NEAR(std::remainder(back.longitude_deg - rlon, 360.0), 0.0, 1e-10) << lat << " " << lon;
        }
      }
    }
  }
  // Metres 6 400 km from the centre: a few ulps.
  EXPECT_LT(worst, 1e-8);
}

TEST(GeographicLibReference, TangentPlaneAgreesWithLocalCartesianTensOfKilometresOut) {
  for (const GeodeticPosition& d : kDatums) {
    GeographicLib::LocalCartesian theirs(d.latitude_deg, d.longitude_deg, d.altitude_m);
    LocalTangentPlane ours;
    ours.reset(d);
    for (double de : {-50000.0, -733.3, 0.0, 12.25, 40000.0}) {
      for (double dn : {-45000.0, -3.5, 0.0, 888.8, 50000.0}) {
        for (double du : {-200.0, 0.0, 35.0}) {
          // A point at that ENU offset per GeographicLib, then both forward.
          double lat, lon, alt;
          theirs.Reverse(de, dn, du, lat, lon, alt);
          const GeodeticPosition p{lat, lon, alt};
          const Eigen::Vector3d mine = ours.forward(p);
          EXPECT_LT((mine - Eigen::Vector3d(de, dn, du)).norm(), 1e-6)
              << d.latitude_deg << " " << d.longitude_deg << " -> " << de << " " << dn << " " << du;
          const GeodeticPosition back = ours.reverse(Eigen::Vector3d(de, dn, du));
          EXPECT_NEAR(back.latitude_deg, lat, 1e-11);
          EXPECT_NEAR(std::remainder(back.longitude_deg - lon, 360.0) * std::cos(lat * M_PI / 180.0), 0.0, 1e-11);
          EXPECT_NEAR(back.altitude_m, alt, 1e-6);
        }
      }
    }
  }
}

}  // namespace
}  // namespace rtfuse::est
