// MpuImu::step(): edge-driven and polled samples, stamps, covariances,
// missing and out-of-order edges, saturation, and no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/imu/mpu_imu.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/scripted_gpio.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace imu_step_test {

using rtfuse::TimeNs;
using rtfuse::drivers::ImuMeasurement;
using rtfuse::drivers::MpuImu;
using rtfuse::drivers::MpuImuConfig;
using rtfuse::drivers::StepResult;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuRegisterFile;
using rtfuse::hal::mock::ScriptedEdgeSource;
using rtfuse::hal::mock::SimClock;
using Chip = rtfuse::sim::MpuChip;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 10 * kMs;  // default config: 1 kHz / (1 + 9)

struct ImuRig {
  explicit ImuRig(const MpuImuConfig& cfg = {}, bool with_line = true)
      : chip(Chip::kMpu6050), clock(2'000 * kMs), imu(cfg, bus, with_line ? &edges : nullptr, clock) {
    EXPECT_TRUE(bus.attach(0x68, chip));
    EXPECT_TRUE(imu.start()) << imu.error();
    t = clock.now();
  }
  // The chip takes a sample (a tiny ramp on x so no two are identical) and,
  // with a line, raises data-ready stamped `stamp`.
  void chip_sample(const Vector3d& accel, const Vector3d& gyro) {
    ++n;
    const double a[3] = {accel.x() + 1e-3 * (n % 7), accel.y(), accel.z()};
    const double g[3] = {gyro.x(), gyro.y(), gyro.z()};
    ASSERT_TRUE(chip.set_sample(a, g, 25.0));
  }
  StepResult sample_at(TimeNs stamp, const Vector3d& accel = Vector3d(0, 0, kG),
                       const Vector3d& gyro = Vector3d::Zero()) {
    chip_sample(accel, gyro);
    edges.push(stamp);
    return imu.step(20 * kMs, &m);
  }
  StepResult next(const Vector3d& accel = Vector3d(0, 0, kG), const Vector3d& gyro = Vector3d::Zero()) {
    t += kPeriod;
    return sample_at(t, accel, gyro);
  }
  MpuRegisterFile chip;
  MockI2cBus bus;
  SimClock clock;
  ScriptedEdgeSource edges;
  MpuImu imu;
  ImuMeasurement m;
  TimeNs t = 0;
  int n = 0;
};

double yaw_of(const Eigen::Quaterniond& q) {
  return std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z()));
}

TEST(MpuImuStep, EdgeDrivenSamplesCarryEdgeStampsAndNoiseModel) {
  ImuRig rig;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(rig.next(Vector3d(0, 0, kG), Vector3d(0, 0, 0.2)), StepResult::kSample) << i;
    EXPECT_EQ(rig.m.stamp, rig.t);
  }
  const ImuMeasurement& m = rig.m;
  EXPECT_TRUE(m.has_orientation);
  EXPECT_TRUE(m.has_angular_velocity);
  EXPECT_TRUE(m.has_linear_acceleration);
  // 49 intervals of 10 ms at 0.2 rad/s after the first sample set the attitude.
  EXPECT_NEAR(yaw_of(m.orientation), 0.098, 1e-3);
  EXPECT_NEAR(m.angular_velocity.z(), 0.2, 2e-4);
  EXPECT_NEAR(m.linear_acceleration.z(), kG, 2e-3);
  EXPECT_NEAR(m.temperature_c, 25.0, 0.01);
  // MPU-6050, DLPF 3 (42 Hz gyro, 44 Hz accel), +-500 deg/s, +-4 g:
  // gyro (0.005 deg/s/rtHz)^2 * 42 Hz + (1/65.5 deg/s)^2/12 = 3.2576e-7 (rad/s)^2;
  // accel (400 ug/rtHz)^2 * 44 Hz + (g/8192)^2/12 = 6.7716e-4 (m/s^2)^2.
  EXPECT_NEAR(m.angular_velocity_cov(0, 0), 3.2576e-7, 1e-10);
  // z also carries the unlearnt gyro bias (no standstill yet): the chip's
  // start-up tolerance, yaw_bias_sigma = 5 deg/s -> 7.6154e-3 (rad/s)^2.
  // (plus its drift allowance since start, 2e-5 rad/s per s).
  EXPECT_GT(m.angular_velocity_cov(2, 2), 3.2576e-7 + 7.6154e-3);
  EXPECT_LT(m.angular_velocity_cov(2, 2), 3.2576e-7 + 7.7e-3);
  EXPECT_NEAR(m.angular_velocity_cov(0, 1), 0.0, 1e-20);
  EXPECT_NEAR(m.linear_acceleration_cov(1, 1), 6.7716e-4, 1e-8);
  EXPECT_GT(m.orientation_cov(0, 0), 0.0);
  EXPECT_GT(m.orientation_cov(2, 2), 0.0);
  EXPECT_EQ(rig.imu.stats().samples, 50);
  EXPECT_EQ(rig.imu.stats().reads, 50);
}

TEST(MpuImuStep, ConfiguredVariancesReplaceTheModel) {
  MpuImuConfig c;
  c.noise.gyro_variance = 1e-4;
  c.noise.accel_variance = 0.01;
  ImuRig rig(c);
  ASSERT_EQ(rig.next(), StepResult::kSample);
  EXPECT_DOUBLE_EQ(rig.m.angular_velocity_cov(1, 1), 1e-4);
  EXPECT_DOUBLE_EQ(rig.m.linear_acceleration_cov(2, 2), 0.01);
}

TEST(MpuImuStep, UpsideDownMountingGivesALevelRobot) {
  MpuImuConfig c;
  c.chip.base_R_imu = Eigen::Quaterniond(Eigen::AngleAxisd(3.14159265358979323846, Vector3d::UnitX()));
  ImuRig rig(c);
  for (int i = 0; i < 10; ++i) ASSERT_EQ(rig.next(Vector3d(0, 0, -kG), Vector3d(0, 0, -0.1)), StepResult::kSample);
  EXPECT_NEAR(rig.m.linear_acceleration.z(), kG, 2e-3);
  EXPECT_NEAR(rig.m.angular_velocity.z(), 0.1, 2e-4);  // chip -z is base +z
  const Eigen::Quaterniond q = rig.m.orientation;
  EXPECT_NEAR(std::abs(q.x()), 0.0, 1e-3);  // level: no roll
  EXPECT_NEAR(std::abs(q.y()), 0.0, 1e-3);
  EXPECT_NEAR(yaw_of(q), 0.009, 1e-4);  // 9 intervals at 0.1 rad/s
}

TEST(MpuImuStep, OutOfOrderEdgeIsDroppedAndCounted) {
  ImuRig rig;
  const TimeNs t0 = rig.t;
  const Vector3d spin(0, 0, 1.0);
  EXPECT_EQ(rig.sample_at(t0 + 10 * kMs, Vector3d(0, 0, kG), spin), StepResult::kSample);
  EXPECT_EQ(rig.sample_at(t0 + 20 * kMs, Vector3d(0, 0, kG), spin), StepResult::kSample);
  const std::int64_t reads = rig.imu.stats().reads;
  EXPECT_EQ(rig.sample_at(t0 + 15 * kMs, Vector3d(0, 0, kG), spin), StepResult::kDropped);
  EXPECT_EQ(rig.sample_at(t0 + 20 * kMs, Vector3d(0, 0, kG), spin), StepResult::kDropped);  // equal is not after
  EXPECT_EQ(rig.imu.stats().reads, reads);  // no read for a bad edge
  EXPECT_EQ(rig.sample_at(t0 + 30 * kMs, Vector3d(0, 0, kG), spin), StepResult::kSample);
  EXPECT_EQ(rig.m.stamp, t0 + 30 * kMs);
  // Two 10 ms steps at 1 rad/s: the dropped edges did not enter dt.
  EXPECT_NEAR(yaw_of(rig.m.orientation), 0.02, 2e-4);
  EXPECT_EQ(rig.imu.stats().out_of_order_edges, 2);
  EXPECT_EQ(rig.imu.stats().samples, 3);
}

TEST(MpuImuStep, ABogusFutureStampDoesNotSilenceTheLineForGood) {
  ImuRig rig;
  const TimeNs t0 = rig.t;
  EXPECT_EQ(rig.sample_at(t0 + 10 * kMs), StepResult::kSample);
  EXPECT_EQ(rig.sample_at(t0 + 10'000 * kMs), StepResult::kSample);  // a glitch 10 s ahead
  for (int i = 0; i < 4; ++i) EXPECT_EQ(rig.sample_at(t0 + (20 + 10 * i) * kMs), StepResult::kDropped) << i;
  EXPECT_EQ(rig.sample_at(t0 + 60 * kMs), StepResult::kSample);  // the fifth in a row: the line is believed
  EXPECT_EQ(rig.sample_at(t0 + 70 * kMs), StepResult::kSample);
  EXPECT_EQ(rig.imu.stats().out_of_order_edges, 5);
  EXPECT_EQ(rig.imu.stats().filter_rejects, 0);
  EXPECT_TRUE(rig.m.has_orientation);
}

TEST(MpuImuStep, TimeoutsAddUpToMissingEdgesThenReinit) {
  MpuImuConfig c;
  c.missing_edge_periods = 3.0;       // 30 ms
  c.missing_edges_before_reinit = 2;
  ImuRig rig(c);
  const int resets = rig.chip.reset_count();
  const StepResult expected[] = {StepResult::kTimeout, StepResult::kTimeout, StepResult::kTimeout,
                                 StepResult::kTimeout,  // 40 ms > 30 ms: missing edge 1
                                 StepResult::kTimeout, StepResult::kTimeout, StepResult::kTimeout,
                                 StepResult::kReinitialised};  // missing edge 2
  for (int i = 0; i < 8; ++i) EXPECT_EQ(rig.imu.step(10 * kMs, &rig.m), expected[i]) << i;
  EXPECT_EQ(rig.imu.stats().edge_timeouts, 8);
  EXPECT_EQ(rig.imu.stats().missing_edges, 2);
  EXPECT_EQ(rig.imu.stats().reinits, 1);
  EXPECT_EQ(rig.chip.reset_count(), resets + 1);
  // Edges flow again after the re-init.
  rig.t = rig.clock.now();
  EXPECT_EQ(rig.next(), StepResult::kSample);
}

TEST(MpuImuStep, AnEdgeBetweenMissingOnesRestartsTheCount) {
  MpuImuConfig c;
  c.missing_edges_before_reinit = 2;
  ImuRig rig(c);
  EXPECT_EQ(rig.imu.step(50 * kMs, &rig.m), StepResult::kTimeout);  // one wait past 30 ms: missing 1
  EXPECT_EQ(rig.next(), StepResult::kSample);
  EXPECT_EQ(rig.imu.step(50 * kMs, &rig.m), StepResult::kTimeout);  // missing 1 again, not 2
  EXPECT_EQ(rig.imu.stats().missing_edges, 2);
  EXPECT_EQ(rig.imu.stats().reinits, 0);
}

TEST(MpuImuStep, PollingWithoutALineStampsWithTheClock) {
  MpuImuConfig c;
  c.poll_rate_hz = 50.0;
  ImuRig rig(c, false);
  ASSERT_TRUE(rig.imu.polling());
  TimeNs prev = rig.clock.now();
  for (int i = 0; i < 10; ++i) {
    rig.chip_sample(Vector3d(0, 0, kG), Vector3d(0, 0, 0.5));
    ASSERT_EQ(rig.imu.step(0, &rig.m), StepResult::kSample) << i;
    EXPECT_EQ(rig.m.stamp, rig.clock.now());
    EXPECT_EQ(rig.m.stamp - prev, 20 * kMs);
    prev = rig.m.stamp;
  }
  EXPECT_NEAR(yaw_of(rig.m.orientation), 9 * 0.02 * 0.5, 2e-4);
  // Stalled for a second: the schedule restarts instead of bursting to catch up.
  rig.clock.advance(1'000 * kMs);
  const TimeNs stall_end = rig.clock.now();
  rig.chip_sample(Vector3d(0, 0, kG), Vector3d::Zero());
  ASSERT_EQ(rig.imu.step(0, &rig.m), StepResult::kSample);
  EXPECT_EQ(rig.m.stamp, stall_end + 20 * kMs);
  EXPECT_EQ(rig.imu.stats().edge_timeouts, 0);
}

TEST(MpuImuStep, PollingDefaultsToTheChipRate) {
  ImuRig rig(MpuImuConfig{}, false);
  const TimeNs before = rig.clock.now();
  rig.chip_sample(Vector3d(0, 0, kG), Vector3d::Zero());
  ASSERT_EQ(rig.imu.step(0, &rig.m), StepResult::kSample);
  EXPECT_EQ(rig.m.stamp - before, kPeriod);
}

TEST(MpuImuStep, SaturatedGyroMarksRatesAndOrientationAbsent) {
  ImuRig rig;
  for (int i = 0; i < 5; ++i) ASSERT_EQ(rig.next(), StepResult::kSample);
  const double yaw_var = rig.m.orientation_cov(2, 2);
  ASSERT_EQ(rig.next(Vector3d(0, 0, kG), Vector3d(0, 0, 10.0)), StepResult::kSample);  // 573 deg/s > 500
  EXPECT_FALSE(rig.m.has_angular_velocity);
  EXPECT_FALSE(rig.m.has_orientation);
  EXPECT_TRUE(rig.m.has_linear_acceleration);
  // At least one more full scale (8.73 rad/s) over 10 ms of unseen rotation.
  const double unseen = 500.0 * 3.14159265358979323846 / 180.0 * 0.01;
  EXPECT_GE(rig.m.orientation_cov(2, 2) - yaw_var, unseen * unseen * 0.999);
  EXPECT_EQ(rig.imu.stats().saturated, 1);
  ASSERT_EQ(rig.next(), StepResult::kSample);
  EXPECT_TRUE(rig.m.has_orientation);
  EXPECT_TRUE(rig.m.has_angular_velocity);
}

TEST(MpuImuStep, SaturatedAccelMarksAccelerationAbsentAndSkipsTheTiltCorrection) {
  ImuRig rig;
  for (int i = 0; i < 5; ++i) ASSERT_EQ(rig.next(), StepResult::kSample);
  ASSERT_EQ(rig.next(Vector3d(5.0 * kG, 0, kG)), StepResult::kSample);  // beyond +-4 g
  EXPECT_FALSE(rig.m.has_linear_acceleration);
  EXPECT_TRUE(rig.m.has_orientation);
  EXPECT_TRUE(rig.m.has_angular_velocity);
  EXPECT_NEAR(rig.m.orientation.angularDistance(Eigen::Quaterniond::Identity()), 0.0, 1e-3);
  EXPECT_EQ(rig.imu.filter().stats().accel_skipped, 1);
}

TEST(MpuImuStep, StepDoesNotAllocateOutsideReinit) {
  MpuImuConfig c;
  c.missing_edges_before_reinit = 1000;
  ImuRig rig(c);
  for (int i = 0; i < 5; ++i) ASSERT_EQ(rig.next(), StepResult::kSample);
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 200; ++i) (void)rig.next(Vector3d(0.1, 0, kG), Vector3d(0.01, 0.02, 0.3));
  for (int i = 0; i < 10; ++i) (void)rig.imu.step(10 * kMs, &rig.m);  // timeouts and missing edges
  (void)rig.sample_at(rig.t - kMs);                                   // out of order
  rig.chip.nack_next(3);
  (void)rig.next();                                                   // a failed read
  (void)rig.next(Vector3d(0, 0, kG), Vector3d(0, 0, 10.0));           // saturated
  const auto stats = rig.imu.stats();
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(stats.samples, 206);
  EXPECT_EQ(stats.missing_edges, 2);  // 40 ms of waiting per missing edge
  EXPECT_EQ(stats.out_of_order_edges, 1);
  EXPECT_EQ(stats.nacks, 1);
  EXPECT_EQ(stats.reinits, 0);
}

// --- gyro bias learnt at standstill ------------------------------------------

// Yaw rate (rad/s), forward speed (m/s) and forward acceleration of a level
// robot: still 3 s, 1 s speeding up into a 0.3 rad/s turn held 20 s, 0.5 s
// easing to a 0.05 rad/s turn held 20 s, 1 s stopping, still 2 s.
struct Motion {
  double yaw_rate, speed, accel;
};
constexpr double kDriveEnd = 47.5;
Motion drive_at(double t) {
  if (t < 3.0) return {0.0, 0.0, 0.0};
  if (t < 4.0) return {0.3 * (t - 3.0), 0.5 * (t - 3.0), 0.5};
  if (t < 24.0) return {0.3, 0.5, 0.0};
  if (t < 24.5) return {0.3 - 0.5 * (t - 24.0), 0.5, 0.0};
  if (t < 44.5) return {0.05, 0.5, 0.0};
  if (t < 45.5) return {0.05 * (45.5 - t), 0.5 * (45.5 - t), -0.5};
  return {0.0, 0.0, 0.0};
}

struct DriveResult {
  double bias_z_after_first_stop = 0.0;
  double bias_sigma_after_first_stop = 0.0;
  double worst_bias_z_in_slow_turn = 0.0;  // farthest from the true 0.007
  double mean_rate_error_fast = 0.0;       // angular_velocity.z - true, averaged
  double mean_rate_error_slow = 0.0;
  double bias_z_end = 0.0;
  double bias_sigma_end_of_turn = 0.0;     // sqrt of the reported z-rate bias variance
  double rate_var_end_of_turn = 0.0;       // angular_velocity_cov(2,2)
  double rate_var_end = 0.0;
  double heading_error_end = 0.0;          // filter yaw - true yaw, wrapped
  std::int64_t still_periods_first_stop = 0;
  std::int64_t still_periods_end_of_turn = 0;
  std::int64_t still_periods_end = 0;
  std::int64_t samples = 0;
  std::size_t allocations = 0;
};

constexpr double kGyroBiasX = 0.005, kGyroBiasY = -0.0035, kGyroBiasZ = 0.007;
constexpr double kGyroNoise = 0.003;   // rad/s per sample at 200 Hz: 5x an MPU-6050's at DLPF 3
constexpr double kAccelNoise = 0.03;   // m/s^2

MpuImuConfig drive_config(bool stillness) {
  MpuImuConfig c;
  c.chip.sample_rate_div = 4;  // 200 Hz
  c.noise.gyro_variance = kGyroNoise * kGyroNoise;
  c.noise.gyro_noise_density = kGyroNoise / std::sqrt(100.0);  // white up to 100 Hz
  c.noise.accel_variance = kAccelNoise * kAccelNoise;
  c.stillness.enabled = stillness;
  return c;
}

DriveResult drive(bool stillness) {
  constexpr TimeNs kStep = 5 * kMs;
  constexpr double kDtS = 0.005;
  ImuRig rig(drive_config(stillness));
  std::mt19937 rng(11);
  std::normal_distribution<double> gn(0.0, kGyroNoise), an(0.0, kAccelNoise);
  DriveResult r;
  double true_yaw = 0.0, fast_sum = 0.0, slow_sum = 0.0;
  int fast_n = 0, slow_n = 0, k = 0;
  bool ok = true;
  rtfuse::test::AllocScope scope;
  for (double t = 0.0; t <= kDriveEnd + 1e-9; t = (++k) * kDtS) {
    const Motion m = drive_at(t);
    const Vector3d gyro(kGyroBiasX + gn(rng), kGyroBiasY + gn(rng), m.yaw_rate + kGyroBiasZ + gn(rng));
    const Vector3d accel(m.accel + an(rng), m.speed * m.yaw_rate + an(rng), kG + an(rng));
    rig.t += kStep;
    ok = ok && rig.sample_at(rig.t, accel, gyro) == StepResult::kSample;
    if (k > 0) true_yaw += m.yaw_rate * kDtS;  // the first sample only sets the attitude
    const double bias_z = rig.imu.filter().gyro_bias().z();
    const double rate_error = rig.m.angular_velocity.z() - m.yaw_rate;
    if (k == 600) {  // t = 3 s, the end of the first stillness
      r.bias_z_after_first_stop = bias_z;
      r.bias_sigma_after_first_stop = std::sqrt(rig.imu.filter().yaw_rate_bias_variance());
      r.still_periods_first_stop = rig.imu.filter().stillness().stats().still_periods;
    }
    if (t >= 4.0 && t < 24.0) {
      fast_sum += rate_error;
      ++fast_n;
    }
    if (t >= 24.5 && t < 44.5) {
      slow_sum += rate_error;
      ++slow_n;
      r.worst_bias_z_in_slow_turn = std::max(r.worst_bias_z_in_slow_turn, std::abs(bias_z - kGyroBiasZ));
      r.bias_sigma_end_of_turn = std::sqrt(rig.imu.filter().yaw_rate_bias_variance());
      r.rate_var_end_of_turn = rig.m.angular_velocity_cov(2, 2);
      r.still_periods_end_of_turn = rig.imu.filter().stillness().stats().still_periods;
    }
  }
  r.allocations = scope.count();
  EXPECT_TRUE(ok);
  r.mean_rate_error_fast = fast_sum / fast_n;
  r.mean_rate_error_slow = slow_sum / slow_n;
  r.bias_z_end = rig.imu.filter().gyro_bias().z();
  r.rate_var_end = rig.m.angular_velocity_cov(2, 2);
  r.heading_error_end = std::remainder(yaw_of(rig.m.orientation) - true_yaw, 2.0 * 3.14159265358979323846);
  r.still_periods_end = rig.imu.filter().stillness().stats().still_periods;
  r.samples = rig.imu.stats().samples;
  return r;
}

TEST(MpuImuStillness, ZBiasLearntAtStandstillIsRemovedAndSurvivesSlowTurns) {
  const DriveResult r = drive(true);
  EXPECT_EQ(r.samples, 9501);
  EXPECT_EQ(r.allocations, 0U);
  EXPECT_NEAR(r.bias_z_after_first_stop, kGyroBiasZ, 5e-4);
  // The reported uncertainty covers the error actually left (3 sigma).
  EXPECT_LE(std::abs(r.bias_z_after_first_stop - kGyroBiasZ), 3.0 * r.bias_sigma_after_first_stop);
  // 0.05 rad/s at 0.5 m/s is constant and |a| ~ g, but above max_rate: not learnt.
  EXPECT_EQ(r.still_periods_first_stop, 1);
  EXPECT_EQ(r.still_periods_end_of_turn, 1);
  EXPECT_LT(r.worst_bias_z_in_slow_turn, 1e-3);
  EXPECT_NEAR(r.mean_rate_error_fast, 0.0, 2e-3);
  EXPECT_NEAR(r.mean_rate_error_slow, 0.0, 2e-3);
  // Without learning the heading would be 0.007 rad/s x 44.5 s = 0.31 rad off.
  EXPECT_LT(std::abs(r.heading_error_end), 0.03);
  // The final stop is still too, and keeps the estimate.
  EXPECT_EQ(r.still_periods_end, 2);
  EXPECT_NEAR(r.bias_z_end, kGyroBiasZ, 5e-4);
  // z-rate variance = noise + the bias residual, which grew with the 41 s
  // since the first stop (2e-5 rad/s per s of drift) and shrank at the second.
  const double noise = kGyroNoise * kGyroNoise;
  EXPECT_NEAR(r.rate_var_end_of_turn, noise + r.bias_sigma_end_of_turn * r.bias_sigma_end_of_turn, 1e-15);
  EXPECT_GT(r.bias_sigma_end_of_turn, 2e-5 * 40.0);
  EXPECT_GT(r.bias_sigma_end_of_turn, r.bias_sigma_after_first_stop);
  EXPECT_GT(r.rate_var_end, noise);
  EXPECT_LT(r.rate_var_end, r.rate_var_end_of_turn);
}

TEST(MpuImuStillness, DisabledTheZBiasStaysInTheRate) {
  const DriveResult r = drive(false);
  // Only Mahony's cross-coupling while accelerating moves it a little.
  EXPECT_LT(std::abs(r.bias_z_end), 5e-4);
  EXPECT_NEAR(r.mean_rate_error_fast, kGyroBiasZ, 5e-4);
  EXPECT_GT(std::abs(r.heading_error_end), 0.25);
  // Never learnt: the z rate says so, with the chip's start-up bias tolerance
  // (5 deg/s) in its variance, so a filter fusing it does not trust it.
  EXPECT_GT(r.rate_var_end, kGyroNoise * kGyroNoise + 7.6e-3);
}

}  // namespace imu_step_test
