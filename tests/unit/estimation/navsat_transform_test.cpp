// robot_localization's navsat_transform semantics: datum, heading
// corrections, lever arm, covariance, rejections, and the filtered fix.
#include "estimation/navsat_transform.hpp"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "geometry/rotation.hpp"
#include "support/alloc_counter.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::est {
namespace navsat_transform_test {

constexpr double kPi = 3.14159265358979323846;
const GeodeticPosition kDatum{52.5163, 13.3777, 34.0};
constexpr TimeNs kSecond = 1'000'000'000;

// A fix at an ENU offset (metres) from kDatum, with a known diagonal covariance.
NavSatFixSample fix_at(double east, double north, double up = 0.0, double var_e = 1.0, double var_n = 1.0) {
  LocalTangentPlane plane;
  plane.reset(kDatum);
  NavSatFixSample f;
  f.status = 0;
  f.position = plane.reverse(Eigen::Vector3d(east, north, up));
  f.covariance_type = 2;
  f.covariance = Eigen::Vector3d(var_e, var_n, 4.0).asDiagonal();
  return f;
}

geometry::RigidTransform pose(double x, double y, double yaw) {
  geometry::RigidTransform t;
  t.translation = Eigen::Vector3d(x, y, 0.0);
  t.rotation = geometry::quaternion_from_rpy(0.0, 0.0, yaw);
  return t;
}

Eigen::Quaterniond imu_yaw(double yaw) { return geometry::quaternion_from_rpy(0.0, 0.0, yaw); }

TEST(NavsatTransform, WaitsForAHeadingBeforeTheDatum) {
  NavsatTransform nt;
  PoseSample out;
  EXPECT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNoHeading);
  EXPECT_FALSE(nt.has_transform());
  EXPECT_EQ(nt.stats().waiting_for_heading, 1);
  nt.set_heading(imu_yaw(0.0));
  EXPECT_EQ(nt.convert(kSecond, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_TRUE(nt.has_transform());
  EXPECT_LT(out.position.norm(), 1e-9);
}

TEST(NavsatTransform, HeadingEastMakesWorldAxesEnuAxes) {
  NavsatTransform nt;
  nt.set_heading(imu_yaw(0.0));  // facing east, world x along the robot
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  ASSERT_EQ(nt.convert(kSecond, fix_at(3.0, 4.0, 0.5), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 3.0, 1e-6);
  EXPECT_NEAR(out.position.y(), 4.0, 1e-6);
  EXPECT_NEAR(out.position.z(), 0.5, 1e-6);
}

TEST(NavsatTransform, NorthReferencedImuNeedsAQuarterTurnOfYawOffset) {
  // An IMU that reads 0 facing north, with the robot facing north: world x
  // is north, so a fix 10 m north is 10 m ahead and one 10 m east is 10 m
  // to the right (world -y).
  NavsatParams p;
  p.yaw_offset_rad = kPi / 2;
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  ASSERT_EQ(nt.convert(kSecond, fix_at(0.0, 10.0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 10.0, 1e-6);
  EXPECT_NEAR(out.position.y(), 0.0, 1e-6);
  ASSERT_EQ(nt.convert(2 * kSecond, fix_at(10.0, 0.0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 0.0, 1e-6);
  EXPECT_NEAR(out.position.y(), -10.0, 1e-6);
}

TEST(NavsatTransform, MagneticDeclinationAddsToTheImuYaw) {
  // A positive declination is counter-clockwise: the IMU reads 0 while the
  // robot faces 0.3 rad north of east.
  NavsatParams p;
  p.magnetic_declination_rad = 0.3;
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  ASSERT_EQ(nt.convert(kSecond, fix_at(10.0 * std::cos(0.3), 10.0 * std::sin(0.3)), pose(0, 0, 0), &out),
            NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 10.0, 1e-6);
  EXPECT_NEAR(out.position.y(), 0.0, 1e-6);
}

TEST(NavsatTransform, TheDatumAnchorsAtTheFiltersPose) {
  // The first fix arrives when the global filter already has the robot at
  // (5, 3) heading 0.4 in map, facing east: map is ENU turned by 0.4.
  NavsatTransform nt;
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(5, 3, 0.4), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 5.0, 1e-6);
  EXPECT_NEAR(out.position.y(), 3.0, 1e-6);
  // Driving 10 m east is 10 m along the robot's heading in map.
  ASSERT_EQ(nt.convert(kSecond, fix_at(10.0, 0.0), pose(15, 3, 0.4), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 5.0 + 10.0 * std::cos(0.4), 1e-6);
  EXPECT_NEAR(out.position.y(), 3.0 + 10.0 * std::sin(0.4), 1e-6);
}

TEST(NavsatTransform, TheLeverArmComesOffWithTheRobotsOrientation) {
  // Antenna 1 m ahead of and 0.5 m above base_link. At the datum the robot
  // faces east; it then turns in place to face west: the antenna moved 2 m
  // west, base_link did not move.
  NavsatParams p;
  p.base_p_antenna = Eigen::Vector3d(1.0, 0.0, 0.5);
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.norm(), 0.0, 1e-6);
  ASSERT_EQ(nt.convert(kSecond, fix_at(-2.0, 0.0), pose(0, 0, kPi), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 0.0, 1e-6);
  EXPECT_NEAR(out.position.y(), 0.0, 1e-6);
  EXPECT_NEAR(out.position.z(), 0.0, 1e-6);
}

TEST(NavsatTransform, CovarianceTurnsWithTheMap) {
  // Robot faces north: world x is north, so east's variance becomes y's.
  NavsatTransform nt;
  nt.set_heading(imu_yaw(kPi / 2));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0, 0, 4.0, 1.0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.covariance(0, 0), 1.0, 1e-9);
  EXPECT_NEAR(out.covariance(1, 1), 4.0, 1e-9);
  EXPECT_NEAR(out.covariance(2, 2), 4.0, 1e-9);
  EXPECT_NEAR(out.covariance(0, 1), 0.0, 1e-9);
  EXPECT_EQ((out.covariance.bottomRightCorner<3, 3>().norm()), 0.0);
}

TEST(NavsatTransform, CovarianceTypesFollowNavSatFix) {
  NavsatParams p;
  p.unknown_horizontal_variance = 9.0;
  p.unknown_vertical_variance = 25.0;
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  NavSatFixSample f = fix_at(0, 0);
  f.covariance_type = 0;  // unknown: whatever it holds, the configured default
  f.covariance.setZero();
  ASSERT_EQ(nt.convert(0, f, pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_DOUBLE_EQ(out.covariance(0, 0), 9.0);
  EXPECT_DOUBLE_EQ(out.covariance(1, 1), 9.0);
  EXPECT_DOUBLE_EQ(out.covariance(2, 2), 25.0);
  f.covariance_type = 1;  // approximated: its diagonal only
  f.covariance << 2.0, 0.5, 0.0, 0.5, 3.0, 0.0, 0.0, 0.0, 6.0;
  ASSERT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_DOUBLE_EQ(out.covariance(0, 1), 0.0);
  EXPECT_NEAR(out.covariance(1, 1), 3.0, 1e-12);
  f.covariance_type = 3;  // known: all of it
  ASSERT_EQ(nt.convert(2 * kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.covariance(0, 1), 0.5, 1e-12);
}

TEST(NavsatTransform, BadFixesAreRejectedAndCounted) {
  NavsatTransform nt;
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  NavSatFixSample f = fix_at(1, 1);
  f.status = -1;
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kNoFix);
  f = fix_at(1, 1);
  f.position.latitude_deg = NAN;
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidPosition);
  f = fix_at(1, 1);
  f.position.longitude_deg = 200.0;
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidPosition);
  f = fix_at(1, 1);
  f.covariance(1, 1) = 0.0;
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidCovariance);
  f = fix_at(1, 1);
  f.covariance(0, 0) = NAN;
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidCovariance);
  f = fix_at(1, 1);
  f.covariance_type = 7;  // no such type
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidCovariance);
  f = fix_at(1, 1);
  f.covariance_type = 3;
  f.covariance(0, 1) = f.covariance(1, 0) = 2.0;  // correlation 2: not a covariance
  EXPECT_EQ(nt.convert(kSecond, f, pose(0, 0, 0), &out), NavsatRejection::kInvalidCovariance);
  EXPECT_EQ(nt.stats().no_fix, 1);
  EXPECT_EQ(nt.stats().invalid_position, 2);
  EXPECT_EQ(nt.stats().invalid_covariance, 4);
  EXPECT_EQ(nt.stats().accepted, 1);
}

TEST(NavsatTransform, AJumpIsGatedUntilTheNewPlaceIsConfirmed) {
  NavsatTransform nt;  // 25 m + 5 m/s
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  // 100 m away 0.2 s later: a multipath jump.
  EXPECT_EQ(nt.convert(kSecond / 5, fix_at(100, 0), pose(0, 0, 0), &out), NavsatRejection::kJump);
  // Back where it should be: accepted, the outlier forgotten.
  EXPECT_EQ(nt.convert(2 * kSecond / 5, fix_at(1, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  // After a minute without fixes the robot may be 300 m away.
  EXPECT_EQ(nt.convert(62 * kSecond, fix_at(250, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  // A lasting offset: rejected twice, then taken as the truth.
  EXPECT_EQ(nt.convert(63 * kSecond, fix_at(250, 200), pose(0, 0, 0), &out), NavsatRejection::kJump);
  EXPECT_EQ(nt.convert(63 * kSecond + kSecond / 5, fix_at(250, 201), pose(0, 0, 0), &out), NavsatRejection::kJump);
  EXPECT_EQ(nt.convert(63 * kSecond + 2 * kSecond / 5, fix_at(250, 202), pose(0, 0, 0), &out),
            NavsatRejection::kNone);
  EXPECT_NEAR(out.position.y(), 202.0, 1e-6);
  EXPECT_EQ(nt.stats().jumps, 3);
  EXPECT_EQ(nt.stats().reanchors, 1);
}

TEST(NavsatTransform, ManualDatumPutsTheWorldOriginThere) {
  NavsatParams p;
  p.manual_datum = true;
  p.datum = {kDatum.latitude_deg, kDatum.longitude_deg, 0.0};
  p.datum_yaw_rad = kPi / 2;  // the robot faces north at the datum
  NavsatTransform nt(p);
  EXPECT_TRUE(nt.has_transform());  // no heading needed
  PoseSample out;
  NavSatFixSample f = fix_at(0.0, 7.0);
  f.position.altitude_m = 0.0;
  ASSERT_EQ(nt.convert(0, f, pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_NEAR(out.position.x(), 7.0, 1e-3);  // ahead
  EXPECT_NEAR(out.position.y(), 0.0, 1e-3);
  nt.reset();
  EXPECT_TRUE(nt.has_transform());
}

TEST(NavsatTransform, ZeroAltitudeFlattensTheOutput) {
  NavsatParams p;
  p.zero_altitude = true;
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  ASSERT_EQ(nt.convert(kSecond, fix_at(1, 2, 30.0), pose(0, 0, 0), &out), NavsatRejection::kNone);
  EXPECT_EQ(out.position.z(), 0.0);
}

TEST(NavsatTransform, FilteredFixIsTheEstimateBackInLatitudeAndLongitude) {
  NavsatParams p;
  p.base_p_antenna = Eigen::Vector3d(0.3, 0.0, 0.8);
  NavsatTransform nt(p);
  nt.set_heading(imu_yaw(0.7));
  PoseSample out;
  ASSERT_EQ(nt.convert(0, fix_at(0, 0), pose(2, -1, 0.2), &out), NavsatRejection::kNone);
  const NavSatFixSample f = fix_at(120.0, -45.0, 2.0, 2.0, 3.0);
  ASSERT_EQ(nt.convert(30 * kSecond, f, pose(0, 0, 1.1), &out), NavsatRejection::kNone);
  // The antenna where the estimate puts it comes back as the raw fix.
  const geometry::RigidTransform world_T_base = [&] {
    geometry::RigidTransform t = pose(0, 0, 1.1);
    t.translation = out.position;
    return t;
  }();
  const Eigen::Vector3d world_p_antenna = world_T_base * p.base_p_antenna;
  const NavSatFixSample back = nt.filtered_fix(world_p_antenna, out.covariance.topLeftCorner<3, 3>());
  EXPECT_NEAR(back.position.latitude_deg, f.position.latitude_deg, 1e-10);
  EXPECT_NEAR(back.position.longitude_deg, f.position.longitude_deg, 1e-10);
  EXPECT_NEAR(back.position.altitude_m, f.position.altitude_m, 1e-6);
  EXPECT_LT((back.covariance - f.covariance).norm(), 1e-9);
  EXPECT_EQ(back.covariance_type, 3);
}

TEST(NavsatTransform, ConvertAllocatesNothing) {
  NavsatTransform nt;
  nt.set_heading(imu_yaw(0.0));
  PoseSample out;
  const NavSatFixSample a = fix_at(0, 0);
  const NavSatFixSample b = fix_at(500, 0);
  test::AllocScope scope;
  test::EigenMallocForbidden eigen_no_malloc;
  for (int i = 0; i < 100; ++i) {
    nt.convert(i * kSecond / 5, i % 7 == 3 ? b : a, pose(0, 0, 0), &out);
    (void)nt.filtered_fix(out.position, out.covariance.topLeftCorner<3, 3>());
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(nt.stats().jumps, 0);
}

TEST(NavsatParams, ValidationNamesTheKey) {
  NavsatParams p;
  EXPECT_STREQ(validate(p), "");
  p.manual_datum = true;
  p.datum.latitude_deg = 95.0;
  EXPECT_NE(std::string(validate(p)).find("datum"), std::string::npos);
  p = NavsatParams{};
  p.yaw_offset_rad = NAN;
  EXPECT_NE(std::string(validate(p)).find("yaw_offset"), std::string::npos);
  p = NavsatParams{};
  p.unknown_horizontal_variance = 0.0;
  EXPECT_NE(std::string(validate(p)).find("unknown covariance"), std::string::npos);
}

}  // namespace navsat_transform_test
}  // namespace rtfuse::est
