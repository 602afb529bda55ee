// StillnessBiasEstimator: learning the gyro bias at standstill, refusing
// turns, the bound on what a slow turn can teach, the hold that keeps the
// start of a motion out, bad input and configuration, and no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "drivers/imu/stillness_bias.hpp"
#include "support/alloc_counter.hpp"

namespace stillness_bias_test {

using rtfuse::drivers::StillnessBiasEstimator;
using rtfuse::drivers::StillnessConfig;
using rtfuse::drivers::StillnessState;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr double kDt = 0.005;  // 200 Hz

// A level robot's IMU: gyro = rate + bias + noise, accel = (forward
// acceleration, centripetal v w, g) + noise.
struct ImuSim {
  explicit ImuSim(double gyro_noise = 0.005, double accel_noise = 0.03, unsigned seed = 7)
      : rng(seed), gn(0.0, gyro_noise), an(0.0, accel_noise) {}
  Vector3d gyro(double yaw_rate) { return Vector3d(0, 0, yaw_rate) + bias + Vector3d(gn(rng), gn(rng), gn(rng)); }
  Vector3d accel(double forward_accel = 0.0, double centripetal = 0.0) {
    return Vector3d(forward_accel, centripetal, kG) + Vector3d(an(rng), an(rng), an(rng));
  }
  // `seconds` at a constant yaw rate and speed; returns the last state.
  StillnessState run(StillnessBiasEstimator& e, Vector3d* est, double seconds, double yaw_rate = 0.0,
                     double speed = 0.0) {
    StillnessState s = StillnessState::kMoving;
    const int n = static_cast<int>(std::lround(seconds / kDt));
    for (int i = 0; i < n; ++i) s = e.update(gyro(yaw_rate), accel(0.0, speed * yaw_rate), kDt, est);
    return s;
  }
  Vector3d bias{0.005, -0.0035, 0.007};
  std::mt19937 rng;
  std::normal_distribution<double> gn, an;
};

TEST(StillnessBias, LearnsTheBiasOnAllAxesAtRest) {
  ImuSim sim;  // 0.005 rad/s per sample: a noisy part
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  EXPECT_EQ(sim.run(e, &est, 0.45), StillnessState::kSettling);
  EXPECT_FALSE(e.learnt());
  EXPECT_EQ(est, Vector3d::Zero());  // nothing before the window
  EXPECT_EQ(sim.run(e, &est, 2.55), StillnessState::kStill);
  ASSERT_TRUE(e.learnt());
  EXPECT_TRUE(e.established());
  // About 2 s averaged: 0.005 / sqrt(400) = 2.5e-4 per axis; 3 sigma.
  EXPECT_NEAR(est.z(), 0.007, 7.5e-4);
  EXPECT_NEAR(est.x(), 0.005, 7.5e-4);
  EXPECT_NEAR(est.y(), -0.0035, 7.5e-4);
  EXPECT_EQ(e.stats().still_periods, 1);
  EXPECT_EQ(e.stats().restarts, 0);  // 5-sigma thresholds: no false motion
  EXPECT_EQ(e.stats().samples, 600);
}

TEST(StillnessBias, AConstantTurnAboveMaxRateIsNeverStill) {
  ImuSim sim;
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  sim.run(e, &est, 3.0);
  const Vector3d learnt = est;
  const auto periods = e.stats().still_periods;
  // 0.05 rad/s at 0.5 m/s: constant gyro, |a| = g + 1e-4: only max_rate tells.
  for (int i = 0; i < 4000; ++i) {
    ASSERT_EQ(e.update(sim.gyro(0.05), sim.accel(0.0, 0.5 * 0.05), kDt, &est), StillnessState::kMoving) << i;
  }
  EXPECT_EQ(est, learnt);
  EXPECT_EQ(e.stats().still_periods, periods);
}

// The documented residual risk, bounded: a turn below max_rate passes for
// stillness; an established bias then moves by at most 2e-4 rad/s per s.
TEST(StillnessBias, ATurnBelowMaxRateMovesAnEstablishedBiasOnlyByTheBound) {
  ImuSim sim(0.001);
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  sim.run(e, &est, 3.0);
  ASSERT_TRUE(e.established());
  const double before = est.z();
  EXPECT_EQ(sim.run(e, &est, 20.0, 0.02, 0.5), StillnessState::kStill);
  const double moved = est.z() - before;
  EXPECT_LE(moved, 2e-4 * 20.0 + 1e-9);
  EXPECT_GT(moved, 3e-3);  // it does move: the gyro alone cannot tell
}

// The samples just before a detected motion are never learnt: a turn that
// starts slowly (0.1 rad/s^2) spends 0.3 s below max_rate.
TEST(StillnessBias, TheStartOfASlowlyStartingTurnIsNotLearnt) {
  ImuSim sim(0.001);
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  sim.run(e, &est, 1.2);
  ASSERT_FALSE(e.established());  // the growing average, unbounded
  for (int i = 1; i <= 400; ++i) e.update(sim.gyro(std::min(0.1 * i * kDt, 0.3)), sim.accel(), kDt, &est);
  EXPECT_FALSE(e.still());
  // Averaging the 0.3 s of ramp (mean 0.015) into 1.5 s would be 3e-3 off.
  EXPECT_NEAR(est.z(), 0.007, 3e-4);
}

TEST(StillnessBias, AStartOrStopInTheAccelerometerRestartsTheWindow) {
  ImuSim sim(0.001, 0.01);
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  sim.run(e, &est, 0.4);
  // Braking at 0.5 m/s^2 without any rotation: |a| stays within tolerance.
  EXPECT_EQ(e.update(sim.gyro(0.0), sim.accel(-0.5), kDt, &est), StillnessState::kSettling);
  EXPECT_EQ(e.stats().restarts, 1);
  // Back to constant speed: that step restarts it again, from there on quiet.
  EXPECT_EQ(sim.run(e, &est, 0.1), StillnessState::kSettling);
  EXPECT_EQ(e.stats().restarts, 2);
  EXPECT_EQ(sim.run(e, &est, 0.35), StillnessState::kSettling);  // 0.45 s since that step
  EXPECT_EQ(sim.run(e, &est, 0.05), StillnessState::kStill);
  EXPECT_EQ(e.stats().still_periods, 1);
}

TEST(StillnessBias, AGapRestartsTheWindow) {
  ImuSim sim(0.001);
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  EXPECT_EQ(sim.run(e, &est, 0.45), StillnessState::kSettling);
  EXPECT_EQ(e.update(sim.gyro(0.0), sim.accel(), 0.2, &est), StillnessState::kMoving);  // > max_dt
  EXPECT_EQ(sim.run(e, &est, 0.45), StillnessState::kSettling);
  e.interrupt(0.05);
  EXPECT_EQ(sim.run(e, &est, 0.45), StillnessState::kSettling);
  EXPECT_EQ(sim.run(e, &est, 0.05), StillnessState::kStill);
}

TEST(StillnessBias, ResidualSigmaIsTheAveragedNoiseThenGrowsWithDrift) {
  ImuSim sim(0.001);
  StillnessConfig c;
  c.bias_drift_rate = 1e-5;
  StillnessBiasEstimator e(c);
  Vector3d est = Vector3d::Zero();
  const double n = 1e-4;  // rad/s/sqrt(Hz)
  EXPECT_EQ(e.residual_sigma(n, 0.08), 0.08);
  sim.run(e, &est, 3.0);
  ASSERT_NEAR(e.learnt_seconds(), 2.0, 1e-12);
  const double settled = e.residual_sigma(n, 0.08);
  EXPECT_NEAR(settled, n / std::sqrt(2.0), 1e-6);  // plus < 0.5 s of drift
  e.interrupt(100.0);
  ASSERT_GE(e.since_learnt(), 100.0);
  ASSERT_LE(e.since_learnt(), 100.26);
  EXPECT_NEAR(e.residual_sigma(n, 0.08), std::hypot(n / std::sqrt(2.0), 1e-5 * e.since_learnt()), 1e-12);
  EXPECT_GT(e.residual_sigma(n, 0.08), 1e-3);
  e.interrupt(1e5);
  EXPECT_EQ(e.residual_sigma(n, 0.08), 0.08);  // never beyond not knowing
}

TEST(StillnessBias, BadInputIsCountedAndChangesNothing) {
  ImuSim sim(0.001);
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  sim.run(e, &est, 1.0);
  const Vector3d before = est;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(e.update(Vector3d(nan, 0, 0), sim.accel(), kDt, &est), StillnessState::kStill);
  EXPECT_EQ(e.update(sim.gyro(0), Vector3d(0, 0, INFINITY), kDt, &est), StillnessState::kStill);
  EXPECT_EQ(e.update(sim.gyro(0), sim.accel(), 0.0, &est), StillnessState::kStill);
  EXPECT_EQ(e.update(sim.gyro(0), sim.accel(), nan, &est), StillnessState::kStill);
  EXPECT_EQ(e.update(sim.gyro(0), sim.accel(), kDt, nullptr), StillnessState::kStill);
  EXPECT_EQ(e.stats().rejected, 5);
  EXPECT_EQ(est, before);
  EXPECT_TRUE(est.allFinite());
}

TEST(StillnessBias, ABadConfigIsNamedAndDisablesLearning) {
  StillnessConfig c;
  c.window = 0.0;
  StillnessBiasEstimator e(c);
  ASSERT_NE(e.config_error(), nullptr);
  EXPECT_NE(std::string(e.config_error()).find("stillness.window"), std::string::npos);
  EXPECT_FALSE(e.enabled());
  Vector3d est(0.001, 0, 0);
  ImuSim sim(0.001);
  EXPECT_EQ(sim.run(e, &est, 3.0), StillnessState::kMoving);
  EXPECT_EQ(est, Vector3d(0.001, 0, 0));
  c = StillnessConfig{};
  c.max_correction_rate = -1.0;
  EXPECT_NE(std::string(rtfuse::drivers::stillness_config_error(c)).find("max_correction_rate"), std::string::npos);
  c.enabled = false;  // a disabled estimator's other fields do not matter
  EXPECT_EQ(rtfuse::drivers::stillness_config_error(c), nullptr);
  EXPECT_EQ(rtfuse::drivers::stillness_config_error(StillnessConfig{}), nullptr);
}

TEST(StillnessBias, UpdateDoesNotAllocate) {
  ImuSim sim;
  StillnessBiasEstimator e;
  Vector3d est = Vector3d::Zero();
  Vector3d g[64], a[64];
  for (int i = 0; i < 64; ++i) {
    g[i] = sim.gyro(i < 32 ? 0.0 : 0.3);
    a[i] = sim.accel();
  }
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 2000; ++i) (void)e.update(g[(i / 200) % 2 == 0 ? i % 32 : 32 + i % 32], a[i % 64], kDt, &est);
  e.interrupt(0.5);
  (void)e.residual_sigma(1e-4, 0.08);
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_GT(e.stats().blocks_learnt, 0);
}

}  // namespace stillness_bias_test
