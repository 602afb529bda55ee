#include "estimation/standstill_gyro_bias.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace standstill_gyro_bias_test {

using rtfuse::TimeNs;
using rtfuse::est::StandstillBiasParams;
using rtfuse::est::StandstillGyroBias;

constexpr TimeNs kMs = 1'000'000;

// A gyro at 100 Hz reading `bias` plus white noise, the wheels at 20 Hz
// reading `speed`, from t0 for `seconds`; the loop's order: by stamp.
void feed(StandstillGyroBias& l, TimeNs t0, double seconds, const Eigen::Vector3d& rate, double speed,
          std::mt19937& rng, double noise = 0.002) {
  std::normal_distribution<double> n(0.0, noise);
  const auto steps = static_cast<int>(std::lround(seconds * 100.0));
  for (int k = 0; k < steps; ++k) {
    const TimeNs t = t0 + k * 10 * kMs;
    if (k % 5 == 0) l.wheels(t, speed, 0.0);
    l.correct(t, rate + Eigen::Vector3d(n(rng), n(rng), n(rng)));
  }
}

TEST(StandstillGyroBias, LearnsTheGyrosRateWhileTheWheelsStandAndTakesItOff) {
  StandstillGyroBias l;
  std::mt19937 rng(1);
  const Eigen::Vector3d bias(0.001, -0.002, 0.003);
  feed(l, 0, 3.0, bias, 0.0, rng);
  EXPECT_GE(l.stats().blocks, 5);
  // The mean of some 250 samples of 0.002 rad/s noise: 1.3e-4 per axis.
  EXPECT_LT((l.bias() - bias).cwiseAbs().maxCoeff(), 6e-4) << l.bias().transpose();
  const Eigen::Vector3d out = l.correct(3000 * kMs, bias);
  EXPECT_LT(out.cwiseAbs().maxCoeff(), 6e-4);
  EXPECT_LT(out.norm(), 0.1 * bias.norm());
}

TEST(StandstillGyroBias, ATurnWhileTheWheelsMoveIsNotABias) {
  // A slow steady turn, the trap of an IMU-only learner: the wheels move.
  StandstillGyroBias l;
  std::mt19937 rng(2);
  feed(l, 0, 10.0, Eigen::Vector3d(0, 0, 0.005), 0.3, rng);
  EXPECT_EQ(l.stats().blocks, 0);
  EXPECT_EQ(l.bias(), Eigen::Vector3d::Zero());
  // And the rate passes through untouched.
  EXPECT_EQ(l.correct(10'000 * kMs, Eigen::Vector3d(0, 0, 0.005)), Eigen::Vector3d(0, 0, 0.005));
}

TEST(StandstillGyroBias, ABlockWaitsForTheWheelsAndAStartDropsIt) {
  StandstillBiasParams p;
  p.block_s = 0.5;
  StandstillGyroBias l(p);
  l.wheels(0, 0.0, 0.0);  // a run opens
  for (int k = 0; k <= 50; ++k) l.correct(k * 10 * kMs, Eigen::Vector3d(0, 0, 0.02));
  // Full (0.5 s) but the wheels have not spoken since its start: not learnt.
  EXPECT_EQ(l.stats().blocks, 0);
  // They start moving: the block may hold the start of the drive.
  l.wheels(510 * kMs, 0.2, 0.0);
  EXPECT_EQ(l.stats().blocks, 0);
  EXPECT_EQ(l.stats().dropped, 1);
  EXPECT_EQ(l.bias(), Eigen::Vector3d::Zero());

  // The same block confirmed by a still wheel sample at its end is learnt.
  StandstillGyroBias m(p);
  m.wheels(0, 0.0, 0.0);
  for (int k = 0; k <= 50; ++k) m.correct(k * 10 * kMs, Eigen::Vector3d(0, 0, 0.02));
  m.wheels(499 * kMs, 0.0, 0.0);  // before its last sample: not yet
  EXPECT_EQ(m.stats().blocks, 0);
  m.wheels(500 * kMs, 0.0, 0.0);
  EXPECT_EQ(m.stats().blocks, 1);
  EXPECT_NEAR(m.bias().z(), 0.02, 1e-15);
}

TEST(StandstillGyroBias, SilentWheelsTeachNothing) {
  // The wheels said "still" twice and then fell silent: the robot may be
  // driving now. The first full block waits for them for ever.
  StandstillGyroBias l;
  l.wheels(0, 0.0, 0.0);
  l.wheels(50 * kMs, 0.0, 0.0);
  for (int k = 0; k < 1000; ++k) l.correct(k * 10 * kMs, Eigen::Vector3d(0, 0, 0.02));
  EXPECT_EQ(l.stats().blocks, 0);
  EXPECT_EQ(l.bias(), Eigen::Vector3d::Zero());
}

TEST(StandstillGyroBias, GyroSamplesBeforeTheWheelsStoppedAreNotLearnt) {
  StandstillGyroBias l;
  l.wheels(0, 0.5, 0.0);
  // Stamped before the first still wheel sample, taken after it.
  l.wheels(1000 * kMs, 0.0, 0.0);
  for (int k = 0; k < 60; ++k) l.correct(400 * kMs + k * 10 * kMs, Eigen::Vector3d(0, 0, 0.1));
  l.wheels(2000 * kMs, 0.0, 0.0);
  EXPECT_EQ(l.stats().blocks, 0);
  EXPECT_EQ(l.bias(), Eigen::Vector3d::Zero());
}

TEST(StandstillGyroBias, WhicheverStreamIsLateOnlyConfirmedSamplesAreLearnt) {
  // The wheels stand from 0 to 2 s and drive from 2.05 s; the gyro reads
  // 0.001 while they stand and 0.05 after. Either stream reaching the loop
  // 0.3 s after the other, the driving samples never reach the bias.
  for (const bool gyro_late : {true, false}) {
    struct Event {
      TimeNs arrival;
      TimeNs stamp;
      bool wheels;
    };
    std::vector<Event> events;
    const TimeNs gyro_lag = gyro_late ? 300 * kMs : 0, wheel_lag = gyro_late ? 0 : 300 * kMs;
    for (int k = 0; k <= 60; ++k) events.push_back({k * 50 * kMs + wheel_lag, k * 50 * kMs, true});
    for (int k = 0; k < 300; ++k) events.push_back({k * 10 * kMs + gyro_lag, k * 10 * kMs, false});
    std::stable_sort(events.begin(), events.end(),
                     [](const Event& x, const Event& y) { return x.arrival < y.arrival; });
    StandstillGyroBias l;
    for (const Event& e : events) {
      if (e.wheels) {
        l.wheels(e.stamp, e.stamp <= 2000 * kMs ? 0.0 : 0.3, 0.0);
      } else {
        l.correct(e.stamp, Eigen::Vector3d(0, 0, e.stamp <= 2000 * kMs ? 0.001 : 0.05));
      }
    }
    EXPECT_GE(l.stats().blocks, 2) << gyro_late;
    EXPECT_NEAR(l.bias().z(), 0.001, 1e-12) << gyro_late;
  }
}

TEST(StandstillGyroBias, AMovingBiasIsFollowedWithTheTimeConstant) {
  StandstillBiasParams p;
  p.time_constant_s = 4.0;
  StandstillGyroBias l(p);
  std::mt19937 rng(4);
  feed(l, 0, 10.0, Eigen::Vector3d(0, 0, 0.01), 0.0, rng, 0.0);
  EXPECT_NEAR(l.bias().z(), 0.01, 1e-12);
  EXPECT_DOUBLE_EQ(l.learnt_s(), 4.0);
  // The part warms: 0.02. After one time constant the estimate has moved
  // by 1 - (4/(4+0.5))^8 = 61 % of the step, not all of it.
  feed(l, 10'000 * kMs, 4.0, Eigen::Vector3d(0, 0, 0.02), 0.0, rng, 0.0);
  EXPECT_GT(l.bias().z(), 0.0150);
  EXPECT_LT(l.bias().z(), 0.0175);
}

TEST(StandstillGyroBias, BadInputIsCountedAndChangesNothing) {
  StandstillGyroBias l;
  std::mt19937 rng(5);
  feed(l, 0, 2.0, Eigen::Vector3d(0.003, 0, 0), 0.0, rng, 0.0);
  const Eigen::Vector3d before = l.bias();
  const auto blocks = l.stats().blocks;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  l.wheels(2000 * kMs, nan, 0.0);
  l.wheels(2000 * kMs, 0.0, std::numeric_limits<double>::infinity());
  l.wheels(100 * kMs, 0.0, 0.0);  // older than the last
  const Eigen::Vector3d bad(nan, 0, 0);
  const Eigen::Vector3d out = l.correct(2000 * kMs, bad);
  EXPECT_TRUE(std::isnan(out.x()));  // passed on for the filter to refuse
  EXPECT_EQ(l.stats().rejected, 4);
  EXPECT_EQ(l.bias(), before);
  EXPECT_EQ(l.stats().blocks, blocks);
  EXPECT_TRUE(l.bias().allFinite());
}

TEST(StandstillGyroBias, ParametersAreChecked) {
  EXPECT_STREQ(rtfuse::est::validate(StandstillBiasParams{}), "");
  StandstillBiasParams p;
  p.block_s = 0.0;
  EXPECT_STRNE(rtfuse::est::validate(p), "");
  p = StandstillBiasParams{};
  p.time_constant_s = 0.1;  // below the block
  EXPECT_STRNE(rtfuse::est::validate(p), "");
  p = StandstillBiasParams{};
  p.still_speed_mps = std::numeric_limits<double>::quiet_NaN();
  EXPECT_STRNE(rtfuse::est::validate(p), "");
}

}  // namespace standstill_gyro_bias_test
