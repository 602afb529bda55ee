#include "vision/egomotion_twist.hpp"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace rtfuse::vision {
namespace egomotion_twist_test {

using Vec6 = Eigen::Matrix<double, 6, 1>;

// The camera's pose after moving with the constant body twist (v, w) for
// dt: exp of the twist, written independently of the code under test
// (rotation by Eigen's angle-axis, translation by integrating finely).
Eigen::Matrix4d integrate(const Eigen::Vector3d& v, const Eigen::Vector3d& w, double dt) {
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  constexpr int kSteps = 20000;
  const double h = dt / kSteps;
  for (int i = 0; i < kSteps; ++i) {
    // Midpoint rule: the rotation half way through the step.
    const Eigen::Matrix3d half =
        w.norm() > 0 ? Eigen::AngleAxisd(0.5 * h * w.norm(), w.normalized()).toRotationMatrix()
                     : Eigen::Matrix3d::Identity();
    pose.topRightCorner<3, 1>() += pose.topLeftCorner<3, 3>() * half * v * h;
    const Eigen::Matrix3d step =
        w.norm() > 0 ? Eigen::AngleAxisd(h * w.norm(), w.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
    pose.topLeftCorner<3, 3>() = pose.topLeftCorner<3, 3>() * step;
  }
  return pose;
}

Egomotion motion(const Vec6& params) {
  Egomotion m;
  m.ok = true;
  m.params = params;
  m.covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-8;
  return m;
}

TEST(EgomotionTwist, IsTheConstantTwistThatMakesTheMotion) {
  const double dt = 1.0 / 30.0;
  Vec6 p;
  p << 0.01, -0.02, 0.005, 0.03, -0.01, -0.05;  // a turn and mostly forward travel
  const CameraTwist tw = egomotion_twist(motion(p), dt);
  ASSERT_TRUE(tw.ok);
  // Moving with that twist for dt puts the camera where the egomotion says:
  // the inverse of the point transform x_cur = T x_prev.
  const Eigen::Matrix4d expected = egomotion_transform(p).inverse();
  const Eigen::Matrix4d got = integrate(tw.linear, tw.angular, dt);
  EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-9) << got << "\n\n" << expected;
  // Not just the translation over dt: the rotation mixes into it.
  EXPECT_GT((tw.linear * dt + p.tail<3>()).norm(), 1e-4);
}

TEST(EgomotionTwist, CovarianceIsTheMotionsPerSecondSquaredLinearFirst) {
  const double dt = 0.05;
  Egomotion m = motion(Vec6::Zero());
  m.covariance.diagonal() << 1e-6, 4e-6, 9e-6, 1e-4, 4e-4, 9e-4;  // rx ry rz tx ty tz
  const CameraTwist tw = egomotion_twist(m, dt);
  ASSERT_TRUE(tw.ok);
  // At rest the map is minus the identity (per axis), so the variances
  // move to linear-then-angular and divide by dt^2.
  const double s = 1.0 / (dt * dt);
  EXPECT_NEAR(tw.covariance(0, 0), 1e-4 * s, 1e-9 * s);
  EXPECT_NEAR(tw.covariance(2, 2), 9e-4 * s, 1e-9 * s);
  EXPECT_NEAR(tw.covariance(3, 3), 1e-6 * s, 1e-11 * s);
  EXPECT_NEAR(tw.covariance(5, 5), 9e-6 * s, 1e-11 * s);
  EXPECT_EQ(tw.covariance, tw.covariance.transpose());
  // Moving, translation and rotation uncertainties couple; still symmetric
  // and positive definite.
  m.params << 0.02, 0.03, -0.01, 0.1, 0.0, 0.5;
  const CameraTwist moving = egomotion_twist(m, dt);
  ASSERT_TRUE(moving.ok);
  EXPECT_EQ(moving.covariance, moving.covariance.transpose());
  EXPECT_GT(moving.covariance.llt().matrixL().toDenseMatrix().diagonal().minCoeff(), 0.0);
}

TEST(EgomotionTwist, RefusesWhatIsNoMotion) {
  Vec6 p = Vec6::Zero();
  EXPECT_FALSE(egomotion_twist(motion(p), 0.0).ok);
  EXPECT_FALSE(egomotion_twist(motion(p), -0.1).ok);
  Egomotion failed = motion(p);
  failed.ok = false;
  EXPECT_FALSE(egomotion_twist(failed, 0.03).ok);
  p(1) = 2.0;  // more than a quarter turn between two frames
  EXPECT_FALSE(egomotion_twist(motion(p), 0.03).ok);
  p(1) = std::nan("");
  EXPECT_FALSE(egomotion_twist(motion(p), 0.03).ok);
  Egomotion bad_cov = motion(Vec6::Zero());
  bad_cov.covariance(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(egomotion_twist(bad_cov, 0.03).ok);
}

}  // namespace egomotion_twist_test
}  // namespace rtfuse::vision
