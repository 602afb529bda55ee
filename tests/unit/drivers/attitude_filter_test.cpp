// AttitudeFilter: initialisation, convergence, bias estimation, yaw
// integration and bad-input handling, for both algorithms.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "drivers/imu/attitude_filter.hpp"
#include "support/alloc_counter.hpp"

namespace attitude_filter_test {

using rtfuse::drivers::AttitudeAlgorithm;
using rtfuse::drivers::AttitudeConfig;
using rtfuse::drivers::AttitudeFilter;
using rtfuse::drivers::AttitudeUpdate;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr double kDt = 0.01;  // 100 Hz

struct Rpy {
  double roll, pitch, yaw;
};

Rpy rpy_of(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  return {std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)),
          std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0)),
          std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))};
}

Eigen::Quaterniond from_rpy(double roll, double pitch, double yaw) {
  return Eigen::AngleAxisd(yaw, Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Vector3d::UnitX());
}

// At rest the accelerometer reads the reaction to gravity: +g up, seen from the body.
Vector3d resting_accel(double roll, double pitch) {
  return from_rpy(roll, pitch, 0.0).conjugate() * Vector3d(0, 0, kG);
}

AttitudeConfig config_for(AttitudeAlgorithm algorithm) {
  AttitudeConfig c;
  c.algorithm = algorithm;
  return c;
}

std::string name_of(const ::testing::TestParamInfo<AttitudeAlgorithm>& info) {
  return info.param == AttitudeAlgorithm::kMadgwick ? "Madgwick" : "Mahony";
}

class AttitudeBoth : public ::testing::TestWithParam<AttitudeAlgorithm> {};

TEST_P(AttitudeBoth, FirstAccelSampleSetsRollAndPitchYawZero) {
  AttitudeFilter f(config_for(GetParam()));
  EXPECT_FALSE(f.initialised());
  EXPECT_EQ(f.update(Vector3d::Zero(), resting_accel(0.3, -0.2), kDt), AttitudeUpdate::kInitialised);
  ASSERT_TRUE(f.initialised());
  const Rpy a = rpy_of(f.orientation());
  EXPECT_NEAR(a.roll, 0.3, 1e-12);
  EXPECT_NEAR(a.pitch, -0.2, 1e-12);
  EXPECT_NEAR(a.yaw, 0.0, 1e-12);
  // Level robot: identity, as sensor_msgs/Imu's z-up convention has it.
  AttitudeFilter level(config_for(GetParam()));
  level.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  EXPECT_NEAR(level.orientation().angularDistance(Eigen::Quaterniond::Identity()), 0.0, 1e-12);
}

TEST_P(AttitudeBoth, RotationAboutZIntegratesYaw) {
  AttitudeFilter f(config_for(GetParam()));
  const Vector3d level(0, 0, kG);
  f.update(Vector3d::Zero(), level, kDt);
  for (int i = 0; i < 200; ++i) ASSERT_EQ(f.update(Vector3d(0, 0, 0.5), level, kDt), AttitudeUpdate::kUpdated);
  const Rpy a = rpy_of(f.orientation());
  EXPECT_NEAR(a.yaw, 1.0, 1e-9);  // 0.5 rad/s for 2 s
  EXPECT_NEAR(a.roll, 0.0, 1e-9);
  EXPECT_NEAR(a.pitch, 0.0, 1e-9);
  EXPECT_NEAR(f.angular_velocity().z(), 0.5, 1e-12);
}

TEST_P(AttitudeBoth, NonFiniteInputIsRejectedAndCounted) {
  AttitudeFilter f(config_for(GetParam()));
  f.update(Vector3d::Zero(), resting_accel(0.1, 0.0), kDt);
  const Eigen::Quaterniond before = f.orientation();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f.update(Vector3d(nan, 0, 0), Vector3d(0, 0, kG), kDt), AttitudeUpdate::kRejectedNonFinite);
  EXPECT_EQ(f.update(Vector3d::Zero(), Vector3d(0, inf, kG), kDt), AttitudeUpdate::kRejectedNonFinite);
  EXPECT_EQ(f.update(Vector3d::Zero(), Vector3d(0, 0, kG), nan), AttitudeUpdate::kRejectedNonFinite);
  EXPECT_EQ(f.update(Vector3d::Zero(), Vector3d(0, 0, kG), 0.0), AttitudeUpdate::kRejectedDt);
  EXPECT_EQ(f.update(Vector3d::Zero(), Vector3d(0, 0, kG), -0.01), AttitudeUpdate::kRejectedDt);
  EXPECT_EQ(f.stats().rejected_non_finite, 3);
  EXPECT_EQ(f.stats().rejected_dt, 2);
  EXPECT_EQ(f.stats().updates, 0);
  EXPECT_TRUE(f.orientation().isApprox(before, 0.0));
  // A saturated accelerometer's values are not looked at.
  EXPECT_EQ(f.update(Vector3d::Zero(), Vector3d(nan, nan, nan), kDt, false), AttitudeUpdate::kUpdated);
  EXPECT_EQ(f.stats().accel_skipped, 1);
}

TEST_P(AttitudeBoth, ZeroAccelGivesNoNaN) {
  AttitudeFilter f(config_for(GetParam()));
  EXPECT_EQ(f.update(Vector3d(0.1, 0, 0), Vector3d::Zero(), kDt), AttitudeUpdate::kWaitingForGravity);
  EXPECT_FALSE(f.initialised());
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  for (int i = 0; i < 100; ++i)
    ASSERT_EQ(f.update(Vector3d(0.1, 0, 0), Vector3d::Zero(), kDt), AttitudeUpdate::kUpdated);
  EXPECT_EQ(f.stats().accel_skipped, 100);
  const Rpy a = rpy_of(f.orientation());
  EXPECT_NEAR(a.roll, 0.1, 1e-9);  // gyro alone: 0.1 rad/s for 1 s
  EXPECT_TRUE(std::isfinite(f.roll_pitch_variance()));
  EXPECT_TRUE(f.orientation_covariance().allFinite());
  EXPECT_TRUE(f.gyro_bias().allFinite());
}

TEST_P(AttitudeBoth, GapReinitialisesRollPitchKeepsYaw) {
  AttitudeConfig c = config_for(GetParam());
  c.max_dt = 0.1;
  c.gap_yaw_rate_sigma = 1.0;
  AttitudeFilter f(c);
  const Vector3d level(0, 0, kG);
  f.update(Vector3d::Zero(), level, kDt);
  for (int i = 0; i < 100; ++i) f.update(Vector3d(0, 0, 0.3), level, kDt);  // yaw 0.3
  const double yaw_var = f.yaw_variance();
  EXPECT_EQ(f.update(Vector3d::Zero(), resting_accel(0.25, 0.1), 0.5), AttitudeUpdate::kGapReinitialised);
  const Rpy a = rpy_of(f.orientation());
  EXPECT_NEAR(a.roll, 0.25, 1e-9);
  EXPECT_NEAR(a.pitch, 0.1, 1e-9);
  EXPECT_NEAR(a.yaw, 0.3, 1e-9);
  // (0.5 s * 1 rad/s)^2 of unseen rotation, plus the gyro terms over the gap.
  EXPECT_GE(f.yaw_variance() - yaw_var, 0.25);
  EXPECT_LT(f.yaw_variance() - yaw_var, 0.25 + c.yaw_bias_sigma * c.yaw_bias_sigma * 2.0);
  EXPECT_EQ(f.stats().gap_reinits, 1);
}

TEST_P(AttitudeBoth, UpdateDoesNotAllocate) {
  AttitudeFilter f(config_for(GetParam()));
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    f.update(Vector3d(0.01, -0.02, 0.3), resting_accel(0.001 * i, 0.0) + Vector3d(0.5, 0, 0), kDt);
    (void)f.orientation_covariance();
  }
  f.update(Vector3d::Zero(), Vector3d::Zero(), kDt);
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), 1.0);
  EXPECT_EQ(scope.count(), 0U);
}

INSTANTIATE_TEST_SUITE_P(Algorithms, AttitudeBoth,
                         ::testing::Values(AttitudeAlgorithm::kMadgwick, AttitudeAlgorithm::kMahony), name_of);

// Started level while the robot stands tilted (roll 0.3, pitch -0.2): the
// accelerometer pulls the estimate over. Mahony's error decays as e^-(kp t):
// 0.36 rad -> 2.4 mrad after 5 s with kp = 1.
TEST(AttitudeMahony, TiltedGravityConvergesWithinFiveSeconds) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMahony);
  c.kp = 1.0;
  c.ki = 0.0;
  AttitudeFilter f(c);
  f.reset(Eigen::Quaterniond::Identity());
  const Vector3d a = resting_accel(0.3, -0.2);
  for (int i = 0; i < 100; ++i) f.update(Vector3d::Zero(), a, kDt);
  Rpy r = rpy_of(f.orientation());
  EXPECT_GT(std::hypot(r.roll - 0.3, r.pitch + 0.2), 0.1);  // after 1 s: e^-1 of the way left
  for (int i = 0; i < 400; ++i) f.update(Vector3d::Zero(), a, kDt);
  r = rpy_of(f.orientation());
  EXPECT_NEAR(r.roll, 0.3, 0.005);
  EXPECT_NEAR(r.pitch, -0.2, 0.005);
}

// Madgwick slews at 2 beta rad/s: 0.36 rad at 0.2 rad/s takes 1.8 s.
TEST(AttitudeMadgwick, TiltedGravityConvergesWithinThreeSeconds) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMadgwick);
  c.beta = 0.1;
  c.zeta = 0.0;
  AttitudeFilter f(c);
  f.reset(Eigen::Quaterniond::Identity());
  const Vector3d a = resting_accel(0.3, -0.2);
  for (int i = 0; i < 100; ++i) f.update(Vector3d::Zero(), a, kDt);
  Rpy r = rpy_of(f.orientation());
  EXPECT_GT(std::hypot(r.roll - 0.3, r.pitch + 0.2), 0.1);
  for (int i = 0; i < 200; ++i) f.update(Vector3d::Zero(), a, kDt);
  r = rpy_of(f.orientation());
  EXPECT_NEAR(r.roll, 0.3, 0.005);
  EXPECT_NEAR(r.pitch, -0.2, 0.005);
}

// A gyro reading (0.02, -0.03, 0) rad/s at rest: the components across gravity
// are observable and estimated; the one along gravity (yaw) is not.
TEST(AttitudeMahony, EstimatesConstantGyroBias) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMahony);
  c.kp = 1.0;
  c.ki = 0.2;
  AttitudeFilter f(c);
  const Vector3d bias(0.02, -0.03, 0.0);
  const Vector3d level(0, 0, kG);
  f.update(bias, level, kDt);
  for (int i = 0; i < 3000; ++i) f.update(bias, level, kDt);  // 30 s
  EXPECT_NEAR(f.gyro_bias().x(), 0.02, 2e-4);
  EXPECT_NEAR(f.gyro_bias().y(), -0.03, 2e-4);
  EXPECT_NEAR(f.gyro_bias().z(), 0.0, 1e-12);
  EXPECT_LT(f.angular_velocity().norm(), 3e-4);
  const Rpy r = rpy_of(f.orientation());
  EXPECT_NEAR(r.roll, 0.0, 1e-3);
  EXPECT_NEAR(r.pitch, 0.0, 1e-3);
}

TEST(AttitudeMadgwick, EstimatesConstantGyroBias) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMadgwick);
  c.beta = 0.05;
  c.zeta = 0.02;
  AttitudeFilter f(c);
  const Vector3d bias(0.02, -0.03, 0.0);
  const Vector3d level(0, 0, kG);
  f.update(bias, level, kDt);
  for (int i = 0; i < 3000; ++i) f.update(bias, level, kDt);  // 30 s
  EXPECT_NEAR(f.gyro_bias().x(), 0.02, 1e-3);
  EXPECT_NEAR(f.gyro_bias().y(), -0.03, 1e-3);
  EXPECT_NEAR(f.gyro_bias().z(), 0.0, 1e-3);
  const Rpy r = rpy_of(f.orientation());
  EXPECT_NEAR(r.roll, 0.0, 2e-3);
  EXPECT_NEAR(r.pitch, 0.0, 2e-3);
}

// Without bias estimation the same gyro offset leaves a standing tilt error
// of bias / kp (Mahony): the estimate above is what removes it.
TEST(AttitudeMahony, WithoutIntegralTheBiasLeavesATiltError) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMahony);
  c.kp = 1.0;
  c.ki = 0.0;
  AttitudeFilter f(c);
  const Vector3d bias(0.02, 0.0, 0.0);
  f.update(bias, Vector3d(0, 0, kG), kDt);
  for (int i = 0; i < 3000; ++i) f.update(bias, Vector3d(0, 0, kG), kDt);
  EXPECT_NEAR(rpy_of(f.orientation()).roll, 0.02, 1e-3);
  EXPECT_EQ(f.gyro_bias().norm(), 0.0);
}

TEST(AttitudeFilterBias, ClampedToMaxBias) {
  AttitudeConfig c = config_for(AttitudeAlgorithm::kMahony);
  c.ki = 5.0;
  c.max_bias = 0.01;
  AttitudeFilter f(c);
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  for (int i = 0; i < 1000; ++i) f.update(Vector3d(0.5, 0, 0), Vector3d(0, 0, kG), kDt);
  EXPECT_LE(std::abs(f.gyro_bias().x()), 0.01);
  EXPECT_NEAR(std::abs(f.gyro_bias().x()), 0.01, 1e-12);
}

// --- with bias learning at standstill ---------------------------------------

using rtfuse::drivers::StillnessConfig;

// A level robot at rest whose gyro reads (0.005, -0.0035, 0.007): the z part
// is invisible to gravity, yet learnt while still, and yaw stops drifting.
TEST_P(AttitudeBoth, StandstillTeachesTheYawBiasAndStopsTheYawDrift) {
  const Vector3d bias(0.005, -0.0035, 0.007);
  const Vector3d level(0, 0, kG);
  AttitudeFilter f(config_for(GetParam()), StillnessConfig{});
  AttitudeFilter blind(config_for(GetParam()));
  f.update(bias, level, kDt);
  blind.update(bias, level, kDt);
  for (int i = 0; i < 300; ++i) {
    f.update(bias, level, kDt);
    blind.update(bias, level, kDt);
  }
  EXPECT_TRUE(f.stillness().still());
  EXPECT_NEAR(f.gyro_bias().z(), 0.007, 1e-5);
  EXPECT_NEAR(f.gyro_bias().x(), 0.005, 2e-4);
  EXPECT_NEAR(f.gyro_bias().y(), -0.0035, 2e-4);
  EXPECT_NEAR(blind.gyro_bias().z(), 0.0, 1e-4);
  const double yaw = rpy_of(f.orientation()).yaw;
  EXPECT_LT(std::abs(yaw), 0.007 * 1.0);  // drifted only until learnt
  for (int i = 0; i < 1000; ++i) {
    f.update(bias, level, kDt);
    blind.update(bias, level, kDt);
  }
  EXPECT_NEAR(rpy_of(f.orientation()).yaw, yaw, 1e-4);     // 10 s more: still
  EXPECT_NEAR(rpy_of(blind.orientation()).yaw, 0.091, 2e-3);  // 0.007 rad/s for 13 s
  EXPECT_NEAR(f.angular_velocity().z(), 0.0, 1e-5);
  // The bias term of the yaw variance stopped growing at yaw_bias_sigma once
  // learnt: under 1 s of it, against 13 s for the blind filter.
  const double s = f.config().yaw_bias_sigma;
  EXPECT_LT(f.yaw_variance(), s * s * 1.0);
  EXPECT_GT(blind.yaw_variance(), s * s * 13.0 * 13.0 * 0.99);
  EXPECT_LT(f.yaw_rate_bias_variance(), 1e-8);
  EXPECT_EQ(blind.yaw_rate_bias_variance(), s * s);
}

TEST(AttitudeStillness, GapsAndSaturatedAccelerometersRestartTheWindow) {
  const Vector3d bias(0, 0, 0.007);
  const Vector3d level(0, 0, kG);
  AttitudeFilter f(AttitudeConfig{}, StillnessConfig{});
  f.update(bias, level, kDt);
  for (int i = 0; i < 45; ++i) f.update(bias, level, kDt);
  EXPECT_EQ(f.update(bias, level, 0.5), AttitudeUpdate::kGapReinitialised);
  for (int i = 0; i < 45; ++i) f.update(bias, level, kDt);
  EXPECT_EQ(f.update(bias, level, kDt, false), AttitudeUpdate::kUpdated);  // saturated
  for (int i = 0; i < 45; ++i) f.update(bias, level, kDt);
  EXPECT_FALSE(f.stillness().still());
  EXPECT_EQ(f.gyro_bias().z(), 0.0);
  EXPECT_EQ(f.stillness().stats().restarts, 2);
  for (int i = 0; i < 100; ++i) f.update(bias, level, kDt);
  EXPECT_TRUE(f.stillness().still());
  EXPECT_NEAR(f.gyro_bias().z(), 0.007, 1e-9);
  // reset() forgets what was learnt.
  f.reset();
  EXPECT_EQ(f.gyro_bias().z(), 0.0);
  EXPECT_FALSE(f.stillness().learnt());
}

}  // namespace attitude_filter_test
