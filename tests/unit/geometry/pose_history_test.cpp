// The poses a late consumer (the mapper) looks up: between two estimates,
// the interpolated pose; "as of" an instant, what was known then, so a
// lookup made late gives what it would have given on time.
#include "geometry/pose_history.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "geometry/rotation.hpp"

namespace pose_history_test {
using namespace rtfuse;              // NOLINT
using namespace rtfuse::geometry;    // NOLINT

RigidTransform pose(double x, double yaw) {
  RigidTransform t;
  t.translation = Eigen::Vector3d(x, 2.0 * x, 0.0);
  t.rotation = quaternion_from_rpy(0.0, 0.0, yaw);
  return t;
}

double yaw_of(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

TEST(PoseHistory, InterpolatesBetweenTheTwoPosesAroundTheStamp) {
  PoseHistory h(8);
  RigidTransform out;
  EXPECT_EQ(h.at(100, &out), PoseLookup::kEmpty);
  ASSERT_TRUE(h.add(100, pose(1.0, 0.1), 100));
  ASSERT_TRUE(h.add(200, pose(2.0, 0.3), 200));
  ASSERT_EQ(h.at(150, &out), PoseLookup::kOk);
  EXPECT_DOUBLE_EQ(out.translation.x(), 1.5);
  EXPECT_DOUBLE_EQ(out.translation.y(), 3.0);
  // nlerp halfway between two yaws is the middle yaw (by symmetry).
  EXPECT_NEAR(yaw_of(out.rotation), 0.2, 1e-12);
  EXPECT_NEAR(out.rotation.norm(), 1.0, 1e-15);
  ASSERT_EQ(h.at(200, &out), PoseLookup::kOk);
  EXPECT_DOUBLE_EQ(out.translation.x(), 2.0);
  EXPECT_EQ(h.at(201, &out), PoseLookup::kNotYet);
  EXPECT_EQ(h.at(99, &out), PoseLookup::kTooOld);
}

TEST(PoseHistory, TakesTheShortWayAcrossThePiSeam) {
  PoseHistory h(4);
  h.add(0, pose(0.0, 3.1), 0);
  h.add(10, pose(0.0, -3.1), 10);
  RigidTransform out;
  ASSERT_EQ(h.at(5, &out), PoseLookup::kOk);
  EXPECT_NEAR(std::abs(yaw_of(out.rotation)), M_PI, 1e-9);
}

TEST(PoseHistory, IgnoresAStampThatDoesNotMoveOnAndForgetsTheOldest) {
  PoseHistory h(3);
  EXPECT_TRUE(h.add(10, pose(1.0, 0.0), 10));
  EXPECT_FALSE(h.add(10, pose(9.0, 0.0), 11));
  EXPECT_FALSE(h.add(5, pose(9.0, 0.0), 12));
  h.add(20, pose(2.0, 0.0), 20);
  h.add(30, pose(3.0, 0.0), 30);
  h.add(40, pose(4.0, 0.0), 40);
  EXPECT_EQ(h.size(), 3);
  RigidTransform out;
  EXPECT_EQ(h.at(15, &out), PoseLookup::kTooOld);
  ASSERT_EQ(h.at(25, &out), PoseLookup::kOk);
  EXPECT_DOUBLE_EQ(out.translation.x(), 2.5);
}

// The mapper's determinism: the same question "as of" the same instant has
// the same answer whether it is asked then or long after.
TEST(PoseHistory, AsOfAnInstantOnlyThePosesKnownThenCount) {
  PoseHistory h(16);
  // Estimates at stamps 100, 200, 300, each known 5 later.
  h.add(100, pose(1.0, 0.0), 105);
  h.add(200, pose(2.0, 0.0), 205);
  RigidTransform on_time, late;
  // Asked at 206 for stamp 250: not covered yet.
  EXPECT_EQ(h.at(250, &on_time, 206), PoseLookup::kNotYet);
  h.add(300, pose(3.0, 0.0), 305);
  // Asked at 400 "as of 206": still not covered, as it was then.
  EXPECT_EQ(h.at(250, &late, 206), PoseLookup::kNotYet);
  EXPECT_EQ(h.at(250, &late, 305), PoseLookup::kOk);
  EXPECT_DOUBLE_EQ(late.translation.x(), 2.5);
  // Stamp 150 was covered by 205: the same pose as of 205 or of now.
  ASSERT_EQ(h.at(150, &on_time, 205), PoseLookup::kOk);
  ASSERT_EQ(h.at(150, &late), PoseLookup::kOk);
  EXPECT_EQ(on_time.translation, late.translation);
  EXPECT_EQ(on_time.rotation.coeffs(), late.rotation.coeffs());
  // Nothing known before 105.
  EXPECT_EQ(h.at(100, &late, 104), PoseLookup::kNotYet);
  EXPECT_EQ(h.at(50, &late, 104), PoseLookup::kTooOld);
}

}  // namespace pose_history_test
