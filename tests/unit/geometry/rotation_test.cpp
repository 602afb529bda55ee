#include "geometry/rotation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "geometry/angles.hpp"

namespace rotation_test {

using namespace rtfuse::geometry;

Eigen::Matrix3d eigen_rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Angles compare modulo 2*pi (roll = pi may come back as -pi).
double angle_diff(double a, double b) { return std::abs(wrap_angle(a - b)); }

TEST(GeometryRotation, HandValues) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE((rotation_from_rpy(0, 0, kPi / 2) * x).isApprox(y, 1e-15));
  EXPECT_TRUE((rotation_from_rpy(0, 0, kPi / 2) * y).isApprox(-x, 1e-15));
  EXPECT_TRUE((rotation_from_rpy(kPi / 2, 0, 0) * y).isApprox(z, 1e-15));
  EXPECT_TRUE((rotation_from_rpy(0, kPi / 2, 0) * z).isApprox(x, 1e-15));
  EXPECT_TRUE((rotation_from_rpy(0, kPi / 2, 0) * x).isApprox(-z, 1e-15));
  EXPECT_TRUE((quaternion_from_rpy(0, 0, kPi / 2) * x).isApprox(y, 1e-15));
  // Fixed axes, roll first: roll pi/2 takes y to z, then yaw pi/2 takes z to z.
  EXPECT_TRUE((rotation_from_rpy(kPi / 2, 0, kPi / 2) * y).isApprox(z, 1e-15));
  // ... and x to y (roll leaves x alone).
  EXPECT_TRUE((rotation_from_rpy(kPi / 2, 0, kPi / 2) * x).isApprox(y, 1e-15));
  const Eigen::Quaterniond q = quaternion_from_rpy(0, 0, kPi / 2);
  EXPECT_NEAR(q.w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(q.x(), 0.0, 1e-15);
  EXPECT_NEAR(q.y(), 0.0, 1e-15);
}

TEST(GeometryRotation, MatchesEigenAngleAxisComposition) {
  for (double roll = -3.0; roll <= 3.0; roll += 0.5) {
    for (double pitch = -1.5; pitch <= 1.5; pitch += 0.25) {
      for (double yaw = -3.1; yaw <= 3.1; yaw += 0.7) {
        const Eigen::Matrix3d expected = eigen_rpy(roll, pitch, yaw);
        ASSERT_TRUE(rotation_from_rpy(roll, pitch, yaw).isApprox(expected, 1e-14)) << roll << " " << pitch << " " << yaw;
        const Eigen::Quaterniond q = quaternion_from_rpy(roll, pitch, yaw);
        ASSERT_NEAR(q.norm(), 1.0, 1e-15);
        ASSERT_TRUE(q.toRotationMatrix().isApprox(expected, 1e-14)) << roll << " " << pitch << " " << yaw;
      }
    }
  }
}

TEST(GeometryRotation, RoundTripOverGridIncludingNearGimbalLock) {
  const double half_pi = kPi / 2;
  const double pitches[] = {-half_pi + 1e-6, -half_pi + 1e-4, -1.2, -0.6, -1e-9, 0.0, 0.3, 0.9, 1.4,
                            half_pi - 1e-4,  half_pi - 1e-6};
  int checked = 0;
  for (int i = -12; i <= 12; ++i) {
    for (int k = -12; k <= 12; ++k) {
      const double roll = i * kPi / 12;  // includes +-pi
      const double yaw = k * kPi / 12;
      for (double pitch : pitches) {
        // Near the singularity asin is ill-conditioned (slope 1/cos(pitch)), in
        // tf2 as here: pitch, and with it the rebuilt matrix, err by about
        // eps / cos(pitch), i.e. ~5e-10 at 1e-6 rad from the lock.
        const double tol = 1e-15 / std::cos(pitch) + 1e-14;
        const Eigen::Vector3d from_q = rpy_from_quaternion(quaternion_from_rpy(roll, pitch, yaw));
        const Eigen::Vector3d from_r = rpy_from_rotation(rotation_from_rpy(roll, pitch, yaw));
        for (const Eigen::Vector3d& rpy : {from_q, from_r}) {
          ASSERT_LT(angle_diff(rpy.x(), roll), tol) << roll << " " << pitch << " " << yaw;
          ASSERT_LT(std::abs(rpy.y() - pitch), tol) << roll << " " << pitch << " " << yaw;
          ASSERT_LT(angle_diff(rpy.z(), yaw), tol) << roll << " " << pitch << " " << yaw;
          ASSERT_LT((rotation_from_rpy(rpy.x(), rpy.y(), rpy.z()) - eigen_rpy(roll, pitch, yaw)).norm(), tol)
              << roll << " " << pitch << " " << yaw;
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 25 * 25 * 11);
}

TEST(GeometryRotation, PitchBeyondHalfPiComesBackAsTf2FirstSolution) {
  // pitch 2.0 is the same rotation as (roll + pi, pi - 2.0, yaw + pi).
  const Eigen::Vector3d rpy = rpy_from_rotation(rotation_from_rpy(0.1, 2.0, 0.2));
  EXPECT_NEAR(rpy.y(), kPi - 2.0, 1e-14);
  EXPECT_LT(angle_diff(rpy.x(), 0.1 + kPi), 1e-14);
  EXPECT_LT(angle_diff(rpy.z(), 0.2 + kPi), 1e-14);
}

// tf2's singular branch: yaw is set to 0, pitch to +-pi/2 (sign opposite to
// r(2,0)) and roll to atan2(r(2,1), r(2,2)).
TEST(GeometryRotation, GimbalLockBranchAsTf2) {
  // Pitch exactly pi/2: sin gives exactly 1 in double, so r(2,0) == -1.
  const Eigen::Matrix3d down = rotation_from_rpy(0.3, kPi / 2, 0.0);
  ASSERT_EQ(down(2, 0), -1.0);
  const Eigen::Vector3d a = rpy_from_rotation(down);
  EXPECT_EQ(a.z(), 0.0);
  EXPECT_EQ(a.y(), kPi / 2);
  EXPECT_NEAR(a.x(), 0.3, 1e-12);
  EXPECT_TRUE(rotation_from_rpy(a.x(), a.y(), a.z()).isApprox(down, 1e-12));

  const Eigen::Matrix3d up = rotation_from_rpy(-0.7, -kPi / 2, 0.0);
  ASSERT_EQ(up(2, 0), 1.0);
  const Eigen::Vector3d b = rpy_from_rotation(up);
  EXPECT_EQ(b.z(), 0.0);
  EXPECT_EQ(b.y(), -kPi / 2);
  EXPECT_NEAR(b.x(), -0.7, 1e-12);

  // A hand-built locked matrix: the branch reads only the bottom row.
  Eigen::Matrix3d m;
  m << 0, 0, 1,  //
      0, 1, 0,   //
      -1, 0, 0;
  const Eigen::Vector3d c = rpy_from_rotation(m);
  EXPECT_EQ(c.x(), std::atan2(0.0, 0.0));
  EXPECT_EQ(c.y(), kPi / 2);
  EXPECT_EQ(c.z(), 0.0);

  // Rounding overshoot past -1 must not reach asin (NaN).
  m(2, 0) = -1.0000000000000002;
  const Eigen::Vector3d d = rpy_from_rotation(m);
  EXPECT_TRUE(d.allFinite());
  EXPECT_EQ(d.y(), kPi / 2);
}

TEST(GeometryRotation, QuaternionNeedNotBeUnitLikeTf2) {
  const Eigen::Quaterniond q = quaternion_from_rpy(0.4, -0.2, 2.5);
  const Eigen::Quaterniond scaled(q.coeffs() * 3.0);
  const Eigen::Quaterniond negated(-q.coeffs());
  const Eigen::Vector3d expected(0.4, -0.2, 2.5);
  EXPECT_TRUE(rpy_from_quaternion(q).isApprox(expected, 1e-14));
  EXPECT_TRUE(rpy_from_quaternion(scaled).isApprox(expected, 1e-14));
  EXPECT_TRUE(rpy_from_quaternion(negated).isApprox(expected, 1e-14));
}

TEST(GeometryRotation, KnownQuaternionToRpy) {
  // 45 degrees about z.
  const Eigen::Quaterniond q(std::cos(kPi / 8), 0, 0, std::sin(kPi / 8));
  const Eigen::Vector3d rpy = rpy_from_quaternion(q);
  EXPECT_NEAR(rpy.x(), 0.0, 1e-15);
  EXPECT_NEAR(rpy.y(), 0.0, 1e-15);
  EXPECT_NEAR(rpy.z(), kPi / 4, 1e-15);
  // 30 degrees about x.
  const Eigen::Vector3d r2 = rpy_from_quaternion(Eigen::Quaterniond(std::cos(kPi / 12), std::sin(kPi / 12), 0, 0));
  EXPECT_NEAR(r2.x(), kPi / 6, 1e-15);
  EXPECT_NEAR(r2.y(), 0.0, 1e-15);
  EXPECT_NEAR(r2.z(), 0.0, 1e-15);
}

}  // namespace rotation_test
