// AttitudeFilter covariances: roll/pitch variance matches the error the
// filter actually makes under accelerometer noise, grows while the robot
// accelerates and relaxes afterwards; yaw variance only grows.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/imu/attitude_filter.hpp"

namespace attitude_covariance_test {

using rtfuse::drivers::AttitudeAlgorithm;
using rtfuse::drivers::AttitudeConfig;
using rtfuse::drivers::AttitudeFilter;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr double kDt = 0.01;

double roll_of(const Eigen::Quaterniond& q) {
  return std::atan2(2 * (q.w() * q.x() + q.y() * q.z()), 1 - 2 * (q.x() * q.x() + q.y() * q.y()));
}

struct Honesty {
  double reported;   // the filter's roll variance at the end
  double empirical;  // mean squared roll error over the run's second half
};

// A level IMU at rest with white accelerometer and gyro noise; the filter's
// reported roll variance against the roll error it really makes.
Honesty run_noisy(const AttitudeConfig& c, double accel_sigma, double gyro_sigma, int samples) {
  AttitudeFilter f(c);
  std::mt19937 rng(12345);
  std::normal_distribution<double> na(0.0, accel_sigma);
  std::normal_distribution<double> ng(0.0, gyro_sigma);
  double sum = 0.0;
  int n = 0;
  for (int i = 0; i < samples; ++i) {
    const Vector3d a(na(rng), na(rng), kG + na(rng));
    const Vector3d w(ng(rng), ng(rng), ng(rng));
    f.update(w, a, kDt);
    if (i >= samples / 2) {
      const double e = roll_of(f.orientation());
      sum += e * e;
      ++n;
    }
  }
  return {f.roll_pitch_variance(), sum / n};
}

AttitudeConfig noisy_config(AttitudeAlgorithm algorithm, double accel_sigma, double gyro_sigma) {
  AttitudeConfig c;
  c.algorithm = algorithm;
  c.ki = 0.0;
  c.zeta = 0.0;
  c.accel_variance = accel_sigma * accel_sigma;
  // White per-sample gyro noise of sigma at rate 1/dt has density sigma sqrt(dt).
  c.gyro_noise_density = gyro_sigma * std::sqrt(kDt);
  return c;
}

// 2000 s at 100 Hz: enough independent stretches (the error's correlation
// time is 1/kp) for the empirical variance to be within a few percent.
TEST(AttitudeCovariance, MahonyRollVarianceMatchesItsErrorUnderNoise) {
  const double sa = 0.05, sg = 0.002;
  AttitudeConfig c = noisy_config(AttitudeAlgorithm::kMahony, sa, sg);
  c.kp = 2.0;
  const Honesty h = run_noisy(c, sa, sg, 200000);
  // Model: P = (alpha^2 sigma^2 + N^2 dt) / (alpha (2 - alpha)), alpha = kp dt.
  const double alpha = 0.02, s2 = sa * sa / (kG * kG), arw = sg * sg * kDt * kDt;
  EXPECT_NEAR(h.reported, (alpha * alpha * s2 + arw) / (alpha * (2 - alpha)), 1e-12);
  EXPECT_GT(h.empirical, 0.85 * h.reported);
  EXPECT_LT(h.empirical, 1.15 * h.reported);
}

struct MadgwickCase {
  double beta;
  double accel_sigma;
};

class AttitudeCovarianceMadgwick : public ::testing::TestWithParam<MadgwickCase> {};

// Small steps against large noise (the linearised regime) and large steps
// against small noise (the estimate chatters by about one step).
TEST_P(AttitudeCovarianceMadgwick, RollVarianceMatchesItsErrorUnderNoise) {
  const double sg = 0.0005;
  AttitudeConfig c = noisy_config(AttitudeAlgorithm::kMadgwick, GetParam().accel_sigma, sg);
  c.beta = GetParam().beta;
  const Honesty h = run_noisy(c, GetParam().accel_sigma, sg, 200000);
  EXPECT_GT(h.empirical, 0.8 * h.reported);
  EXPECT_LT(h.empirical, 1.15 * h.reported);
}

INSTANTIATE_TEST_SUITE_P(Regimes, AttitudeCovarianceMadgwick,
                         ::testing::Values(MadgwickCase{0.01, 0.1}, MadgwickCase{0.1, 0.026}));

TEST(AttitudeCovariance, HigherGainTrustsTheNoisyAccelerometerMore) {
  const double sa = 0.05, sg = 0.0005;
  AttitudeConfig slow = noisy_config(AttitudeAlgorithm::kMahony, sa, sg);
  slow.kp = 0.5;
  AttitudeConfig fast = slow;
  fast.kp = 10.0;
  const Honesty hs = run_noisy(slow, sa, sg, 4000);
  const Honesty hf = run_noisy(fast, sa, sg, 4000);
  EXPECT_GT(hf.reported, 10.0 * hs.reported);
  EXPECT_GT(hf.empirical, 5.0 * hs.empirical);
  // Right after the first sample the only information is that sample.
  AttitudeFilter f(slow);
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  EXPECT_NEAR(f.roll_pitch_variance(), sa * sa / (kG * kG), 1e-15);
}

// A robot accelerating forward at 2 m/s^2 for 2 s: the accelerometer points
// 0.2 rad off vertical and drags the estimate along; the variance must cover
// that error while it lasts and relax once |a| is back at g.
TEST(AttitudeCovariance, AccelerationInflatesRollPitchAndItDecaysAfter) {
  AttitudeConfig c;
  c.algorithm = AttitudeAlgorithm::kMahony;
  c.kp = 1.0;
  c.ki = 0.0;
  c.gravity_tolerance = 0.0;  // a calibrated accelerometer: |a| at rest is g
  AttitudeFilter f(c);
  const Vector3d still(0, 0, kG);
  f.update(Vector3d::Zero(), still, kDt);
  for (int i = 0; i < 1000; ++i) f.update(Vector3d::Zero(), still, kDt);
  const double rest = f.roll_pitch_variance();

  double worst_ratio = 0.0;  // squared error over the reported variance
  for (int i = 0; i < 200; ++i) {
    f.update(Vector3d::Zero(), Vector3d(2.0, 0, kG), kDt);
    const double pitch_err = 2 * std::asin(std::clamp(f.orientation().y(), -1.0, 1.0));
    // |a| grows by 0.2 m/s^2 only: the averaged excess needs a few samples
    // to rise above the noise threshold.
    if (i >= 5) worst_ratio = std::max(worst_ratio, pitch_err * pitch_err / f.roll_pitch_variance());
  }
  const double accelerating = f.roll_pitch_variance();
  EXPECT_GT(accelerating, 100.0 * rest);
  EXPECT_LT(worst_ratio, 1.0);  // the error stayed inside one sigma of the report

  for (int i = 0; i < 1000; ++i) f.update(Vector3d::Zero(), still, kDt);  // 10 time constants
  EXPECT_LT(f.roll_pitch_variance(), 2.0 * rest);
  EXPECT_GE(f.roll_pitch_variance(), rest * 0.999);
}

TEST(AttitudeCovariance, YawVarianceGrowsWithTime) {
  AttitudeConfig c;
  c.gyro_noise_density = 1e-3;
  c.yaw_bias_sigma = 0.002;
  AttitudeFilter f(c);
  const Vector3d still(0, 0, kG);
  f.update(Vector3d::Zero(), still, kDt);
  double prev = f.yaw_variance();
  EXPECT_EQ(prev, 0.0);  // yaw is 0 by definition at the start
  for (int i = 0; i < 10000; ++i) {
    f.update(Vector3d::Zero(), still, kDt);
    ASSERT_GT(f.yaw_variance(), prev);
    prev = f.yaw_variance();
  }
  // 100 s: N^2 T + (sigma_b T)^2 = 1e-4 + 0.04.
  EXPECT_NEAR(f.yaw_variance(), 1e-6 * 100 + 0.002 * 0.002 * 100 * 100, 1e-9);
  EXPECT_NEAR(f.orientation_covariance()(2, 2), f.yaw_variance(), 1e-15);
  // The accelerometer keeps roll/pitch bounded meanwhile.
  EXPECT_LT(f.roll_pitch_variance(), 1e-4);
}

TEST(AttitudeCovariance, InflateAddsOutsideUncertainty) {
  AttitudeFilter f;
  f.update(Vector3d::Zero(), Vector3d(0, 0, kG), kDt);
  const double rp = f.roll_pitch_variance();
  const double yaw = f.yaw_variance();
  f.inflate(0.01, 0.04);
  EXPECT_NEAR(f.roll_pitch_variance() - rp, 0.01, 1e-15);
  EXPECT_NEAR(f.yaw_variance() - yaw, 0.04, 1e-15);
  f.inflate(-1.0, std::nan(""));
  EXPECT_NEAR(f.roll_pitch_variance() - rp, 0.01, 1e-15);
}

}  // namespace attitude_covariance_test
