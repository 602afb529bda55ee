// Wheel odometry on known motions with hand-computed numbers, the noise
// model, fault handling, and the chain from CANopen nodes to a pose.
#include "drivers/wheel/wheel_odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "drivers/canopen/canopen_encoders.hpp"
#include "sim/devices/canopen_encoder_node.hpp"
#include "hal/mock/mock_can_bus.hpp"
#include "support/alloc_counter.hpp"

namespace wheel_odometry_test {

using rtfuse::TimeNs;
using rtfuse::drivers::DriveKinematics;
using rtfuse::drivers::EncoderReading;
using rtfuse::drivers::PlanarPose;
using rtfuse::drivers::WheelOdometry;
using rtfuse::drivers::WheelOdometryConfig;
using rtfuse::drivers::WheelSide;
using rtfuse::drivers::WheelTwist;

constexpr double kPi = 3.14159265358979323846;
constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kStep = 20 * kMs;  // 50 Hz sample sets
constexpr double kDt = 0.02;
// r = 0.1 m, 1000 counts per wheel turn: 2*pi*0.1/1000 m per count, so 50
// counts per 20 ms is exactly pi/2 m/s.
constexpr double kMetersPerCount = 2.0 * kPi * 0.1 / 1000.0;

WheelOdometryConfig diff_config() {
  WheelOdometryConfig c;
  c.kinematics = DriveKinematics::kDifferential;
  c.track_width_m = 0.5;
  c.wheel_radius_m = 0.1;
  c.counts_per_rev = 250.0;
  c.gear_ratio = 4.0;  // 250 counts per motor turn, 4 motor turns per wheel turn
  c.wheel_count = 2;
  c.wheels[0] = {0, WheelSide::kLeft, 1};
  c.wheels[1] = {1, WheelSide::kRight, 1};
  c.slip_fraction = 0.02;
  c.vx_sigma_floor_mps = 0.005;
  c.vyaw_sigma_floor_radps = 0.005;
  return c;
}

std::unique_ptr<WheelOdometry> make(const WheelOdometryConfig& c) {
  std::string error;
  auto odo = WheelOdometry::create(c, &error);
  EXPECT_NE(odo, nullptr) << error;
  return odo;
}

EncoderReading at(std::int64_t counts, TimeNs stamp, bool valid = true, std::uint32_t segment = 0) {
  EncoderReading r;
  r.valid = valid;
  r.counts = counts;
  r.stamp = stamp;
  r.segment = segment;
  r.health = valid ? rtfuse::drivers::EncoderHealth::kOk : rtfuse::drivers::EncoderHealth::kSilent;
  return r;
}

// Drives `steps` sample sets with constant per-step counts on each side.
struct Drive {
  explicit Drive(WheelOdometry& o) : odo(o) {}
  WheelOdometry& odo;
  std::int64_t left = 0;
  std::int64_t right = 0;
  TimeNs t = 0;
  int outputs = 0;
  WheelTwist last;

  void run(int steps, std::int64_t dl, std::int64_t dr) {
    for (int i = 0; i < steps; ++i) {
      const EncoderReading r[2] = {at(left, t), at(right, t)};
      if (odo.update(r, 2, &last)) ++outputs;
      left += dl;
      right += dr;
      t += kStep;
    }
  }
};

TEST(WheelOdometry, StraightLine) {
  auto odo = make(diff_config());
  EXPECT_NEAR(odo->meters_per_count(), kMetersPerCount, 1e-15);
  Drive d{*odo};
  d.run(51, 50, 50);
  EXPECT_EQ(d.outputs, 50);  // the first set only seeds
  EXPECT_EQ(odo->stats().reseeds, 1);
  EXPECT_NEAR(d.last.vx, kPi / 2, 1e-12);
  EXPECT_NEAR(d.last.vyaw, 0.0, 1e-12);
  EXPECT_EQ(d.last.dt_ns, kStep);
  EXPECT_EQ(d.last.stamp, 50 * kStep);
  EXPECT_EQ(d.last.wheels_used, 2);
  EXPECT_NEAR(odo->pose().x, 50 * kDt * kPi / 2, 1e-12);  // 1 s at pi/2 m/s
  EXPECT_NEAR(odo->pose().y, 0.0, 1e-12);
  EXPECT_NEAR(odo->pose().yaw, 0.0, 1e-12);
  EXPECT_EQ(odo->pose_stamp(), 50 * kStep);
}

TEST(WheelOdometry, SpinInPlace) {
  auto odo = make(diff_config());
  Drive d{*odo};
  d.run(13, -50, 50);  // 12 outputs, 0.24 s
  EXPECT_NEAR(d.last.vx, 0.0, 1e-12);
  EXPECT_NEAR(d.last.vyaw, kPi / 0.5, 1e-12);  // (pi/2 + pi/2) / 0.5 m track
  EXPECT_NEAR(odo->pose().yaw, 2 * kPi * 0.24, 1e-12);
  EXPECT_NEAR(odo->pose().x, 0.0, 1e-12);
  EXPECT_NEAR(odo->pose().y, 0.0, 1e-12);
}

TEST(WheelOdometry, ArcIsIntegratedExactly) {
  auto odo = make(diff_config());
  Drive d{*odo};
  // v_l = pi/4, v_r = 3pi/4: vx = pi/2, vyaw = pi rad/s, radius 0.5 m.
  d.run(26, 25, 75);  // 25 outputs = 0.5 s = a quarter circle
  EXPECT_NEAR(d.last.vx, kPi / 2, 1e-12);
  EXPECT_NEAR(d.last.vyaw, kPi, 1e-12);
  EXPECT_NEAR(d.last.v_left, kPi / 4, 1e-12);
  EXPECT_NEAR(d.last.v_right, 3 * kPi / 4, 1e-12);
  EXPECT_NEAR(odo->pose().x, 0.5, 1e-12);
  EXPECT_NEAR(odo->pose().y, 0.5, 1e-12);
  EXPECT_NEAR(odo->pose().yaw, kPi / 2, 1e-12);
  // A quarter more: at (0, 1) facing backwards, yaw wrapped into (-pi, pi].
  d.run(25, 25, 75);
  EXPECT_NEAR(odo->pose().x, 0.0, 1e-12);
  EXPECT_NEAR(odo->pose().y, 1.0, 1e-12);
  EXPECT_NEAR(std::fabs(odo->pose().yaw), kPi, 1e-12);
}

TEST(WheelOdometry, SkidSteerUsesTheEffectiveTrack) {
  WheelOdometryConfig c = diff_config();
  c.kinematics = DriveKinematics::kSkidSteer;
  c.skid_track_factor = 1.5;
  c.skid_yaw_variance_per_mps = 0.01;
  c.wheel_count = 4;
  c.wheels[0] = {0, WheelSide::kLeft, 1};
  c.wheels[1] = {1, WheelSide::kLeft, 1};
  c.wheels[2] = {2, WheelSide::kRight, 1};
  c.wheels[3] = {3, WheelSide::kRight, 1};
  auto odo = make(c);
  EXPECT_NEAR(odo->effective_track_m(), 0.75, 1e-15);
  WheelTwist tw;
  const EncoderReading a[4] = {at(0, 0), at(0, 0), at(0, 0), at(0, 0)};
  EXPECT_FALSE(odo->update(a, 4, &tw));
  // Front and rear wheels of a side disagree (scrub): the side uses their mean.
  const EncoderReading b[4] = {at(-48, kStep), at(-52, kStep), at(50, kStep), at(50, kStep)};
  ASSERT_TRUE(odo->update(b, 4, &tw));
  EXPECT_NEAR(tw.vx, 0.0, 1e-12);
  EXPECT_NEAR(tw.vyaw, kPi / 0.75, 1e-12);
  EXPECT_EQ(tw.wheels_used, 4);
  // Yaw variance: both sides' speed variances over B^2, the floor, and the
  // scrub term 0.01 * |v_r - v_l| = 0.01 * pi.
  const double q = kMetersPerCount / kDt;
  const double var_side = std::pow(0.02 * kPi / 2, 2) + q * q / 2;
  EXPECT_NEAR(tw.var_vyaw, 2 * var_side / (0.75 * 0.75) + 0.005 * 0.005 + 0.01 * kPi, 1e-12);
}

TEST(WheelOdometry, CovarianceNumbersAndCorrelation) {
  auto odo = make(diff_config());
  Drive d{*odo};
  d.run(3, 25, 75);
  const double q = kMetersPerCount / kDt;  // one count per 20 ms = pi/100 m/s
  const double var_l = std::pow(0.02 * kPi / 4, 2) + q * q;
  const double var_r = std::pow(0.02 * 3 * kPi / 4, 2) + q * q;
  EXPECT_NEAR(d.last.var_vx, (var_l + var_r) / 4 + 0.005 * 0.005, 1e-15);
  EXPECT_NEAR(d.last.var_vyaw, (var_l + var_r) / 0.25 + 0.005 * 0.005, 1e-15);
  // The faster right side is the less certain: vx and vyaw err together.
  EXPECT_NEAR(d.last.cov_vx_vyaw, (var_r - var_l) / (2 * 0.5), 1e-15);
  EXPECT_GT(d.last.cov_vx_vyaw, 0.0);
  // A valid covariance: |cov| <= sqrt(var_vx * var_vyaw).
  EXPECT_LT(d.last.cov_vx_vyaw * d.last.cov_vx_vyaw, d.last.var_vx * d.last.var_vyaw);
}

TEST(WheelOdometry, CovarianceGrowsWithSpeedAndSlip) {
  auto twist_at = [](std::int64_t counts_per_step, double slip) {
    WheelOdometryConfig c = diff_config();
    c.slip_fraction = slip;
    auto odo = make(c);
    Drive d{*odo};
    d.run(3, counts_per_step, counts_per_step);
    return d.last;
  };
  const WheelTwist still = twist_at(0, 0.02);
  const WheelTwist slow = twist_at(20, 0.02);
  const WheelTwist fast = twist_at(200, 0.02);
  const WheelTwist fast_slippy = twist_at(200, 0.10);
  // Standing still: quantisation and floor only.
  const double q = kMetersPerCount / kDt;
  EXPECT_NEAR(still.var_vx, q * q / 2 + 0.005 * 0.005, 1e-15);
  EXPECT_LT(still.var_vx, slow.var_vx);
  EXPECT_LT(slow.var_vx, fast.var_vx);
  EXPECT_LT(fast.var_vx, fast_slippy.var_vx);
  EXPECT_LT(still.var_vyaw, slow.var_vyaw);
  EXPECT_LT(slow.var_vyaw, fast.var_vyaw);
  EXPECT_LT(fast.var_vyaw, fast_slippy.var_vyaw);
  // At 2*pi m/s the slip term dominates: sigma_vx ~ slip * v / sqrt(2).
  const double v = 200 * kMetersPerCount / kDt;
  EXPECT_NEAR(fast_slippy.var_vx, (2 * std::pow(0.10 * v, 2) + 2 * q * q) / 4 + 0.005 * 0.005, 1e-12);
}

TEST(WheelOdometry, SkidSteerYawVarianceGrowsWithTheSpeedDifference) {
  WheelOdometryConfig c = diff_config();
  c.kinematics = DriveKinematics::kSkidSteer;
  c.skid_track_factor = 1.2;
  c.skid_yaw_variance_per_mps = 0.05;
  c.slip_fraction = 0.0;
  auto yaw_var = [&](std::int64_t dl, std::int64_t dr) {
    auto odo = make(c);
    Drive d{*odo};
    d.run(3, dl, dr);
    return d.last.var_vyaw;
  };
  const double straight = yaw_var(50, 50);
  const double turn = yaw_var(25, 75);
  const double spin = yaw_var(-50, 50);
  EXPECT_NEAR(turn - straight, 0.05 * (kPi / 2), 1e-12);
  EXPECT_NEAR(spin - straight, 0.05 * kPi, 1e-12);
}

TEST(WheelOdometry, SignFlipsAMirroredMotor) {
  WheelOdometryConfig c = diff_config();
  c.wheels[1].sign = -1;  // right motor mounted mirrored: counts fall going forward
  auto odo = make(c);
  WheelTwist tw;
  const EncoderReading a[2] = {at(1000, 0), at(1000, 0)};
  const EncoderReading b[2] = {at(1050, kStep), at(950, kStep)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  ASSERT_TRUE(odo->update(b, 2, &tw));
  EXPECT_NEAR(tw.vx, kPi / 2, 1e-12);
  EXPECT_NEAR(tw.vyaw, 0.0, 1e-12);
  // Without the sign the same counts are a spin.
  auto plain = make(diff_config());
  EXPECT_FALSE(plain->update(a, 2, &tw));
  ASSERT_TRUE(plain->update(b, 2, &tw));
  EXPECT_NEAR(tw.vx, 0.0, 1e-12);
  EXPECT_NEAR(tw.vyaw, -kPi / 0.5, 1e-12);
}

TEST(WheelOdometry, EncoderIndexMapsWheelsToReadings) {
  WheelOdometryConfig c = diff_config();
  c.wheels[0] = {3, WheelSide::kLeft, 1};
  c.wheels[1] = {1, WheelSide::kRight, 1};
  auto odo = make(c);
  WheelTwist tw;
  const EncoderReading a[4] = {at(0, 0, false), at(0, 0), at(0, 0, false), at(0, 0)};
  const EncoderReading b[4] = {at(999, kStep, false), at(75, kStep), at(-999, kStep, false), at(25, kStep)};
  EXPECT_FALSE(odo->update(a, 4, &tw));
  ASSERT_TRUE(odo->update(b, 4, &tw));
  EXPECT_NEAR(tw.v_left, kPi / 4, 1e-12);
  EXPECT_NEAR(tw.v_right, 3 * kPi / 4, 1e-12);
}

TEST(WheelOdometry, MeanOfTheValidWheelsOfASide) {
  WheelOdometryConfig c = diff_config();
  c.wheel_count = 4;
  c.wheels[0] = {0, WheelSide::kLeft, 1};
  c.wheels[1] = {1, WheelSide::kLeft, 1};
  c.wheels[2] = {2, WheelSide::kRight, 1};
  c.wheels[3] = {3, WheelSide::kRight, 1};
  auto odo = make(c);
  WheelTwist tw;
  const EncoderReading a[4] = {at(0, 0), at(0, 0), at(0, 0), at(0, 0)};
  const EncoderReading b[4] = {at(50, kStep), at(500, kStep, false), at(40, kStep), at(60, kStep)};
  EXPECT_FALSE(odo->update(a, 4, &tw));
  ASSERT_TRUE(odo->update(b, 4, &tw));
  EXPECT_EQ(tw.wheels_used, 3);
  EXPECT_NEAR(tw.v_left, kPi / 2, 1e-12);
  EXPECT_NEAR(tw.v_right, kPi / 2, 1e-12);
  // Quantisation of the left side, one wheel, is twice that of the right, two.
  const double q = kMetersPerCount / kDt;
  EXPECT_NEAR(tw.cov_vx_vyaw, (q * q / 2 - q * q) / (2 * 0.5), 1e-15);
  // Wheel 1 was invalid in the previous set: it sits this one out too.
  const EncoderReading c3[4] = {at(100, 2 * kStep), at(550, 2 * kStep), at(90, 2 * kStep), at(110, 2 * kStep)};
  ASSERT_TRUE(odo->update(c3, 4, &tw));
  EXPECT_EQ(tw.wheels_used, 3);
  const EncoderReading c4[4] = {at(150, 3 * kStep), at(600, 3 * kStep), at(140, 3 * kStep), at(160, 3 * kStep)};
  ASSERT_TRUE(odo->update(c4, 4, &tw));
  EXPECT_EQ(tw.wheels_used, 4);
}

TEST(WheelOdometry, ASideWithoutValidWheelGivesNothingAndReseeds) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading a[2] = {at(0, 0), at(0, 0)};
  const EncoderReading b[2] = {at(50, kStep), at(50, kStep, false)};
  const EncoderReading c[2] = {at(100, 2 * kStep), at(100, 2 * kStep)};
  const EncoderReading d[2] = {at(150, 3 * kStep), at(150, 3 * kStep)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  EXPECT_FALSE(odo->update(b, 2, &tw));
  EXPECT_EQ(odo->stats().no_side, 1);
  EXPECT_FALSE(odo->update(c, 2, &tw)) << "right wheel has no valid previous sample";
  EXPECT_EQ(odo->stats().no_side, 2);
  ASSERT_TRUE(odo->update(d, 2, &tw));
  EXPECT_NEAR(tw.vx, kPi / 2, 1e-12);
  // The pose only moved over the interval it could measure.
  EXPECT_NEAR(odo->pose().x, 50 * kMetersPerCount, 1e-12);
}

TEST(WheelOdometry, AllInvalidThenBackReseeds) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading a[2] = {at(0, 0), at(0, 0)};
  const EncoderReading none[2] = {at(0, kStep, false), at(0, kStep, false)};
  const EncoderReading c[2] = {at(100, 2 * kStep), at(100, 2 * kStep)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  EXPECT_FALSE(odo->update(none, 2, &tw));
  EXPECT_FALSE(odo->update(c, 2, &tw));
  EXPECT_EQ(odo->stats().outputs, 0);
  EXPECT_EQ(odo->stats().no_side, 2);
}

TEST(WheelOdometry, NewSegmentMeansNoDifference) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading a[2] = {at(0, 0), at(0, 0)};
  const EncoderReading b[2] = {at(5000, kStep, true, 1), at(50, kStep)};  // left re-based after a gap
  const EncoderReading c[2] = {at(5050, 2 * kStep, true, 1), at(100, 2 * kStep)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  EXPECT_FALSE(odo->update(b, 2, &tw));
  EXPECT_EQ(odo->stats().no_side, 1);
  ASSERT_TRUE(odo->update(c, 2, &tw));
  EXPECT_NEAR(tw.vx, kPi / 2, 1e-12);
}

TEST(WheelOdometry, GapLongerThanMaxGapReseeds) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading a[2] = {at(0, 0), at(0, 0)};
  const EncoderReading b[2] = {at(1000, 600 * kMs), at(1000, 600 * kMs)};
  const EncoderReading c[2] = {at(1050, 620 * kMs), at(1050, 620 * kMs)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  EXPECT_FALSE(odo->update(b, 2, &tw));
  EXPECT_EQ(odo->stats().reseeds, 2);
  ASSERT_TRUE(odo->update(c, 2, &tw));
  EXPECT_EQ(tw.dt_ns, 20 * kMs);
  EXPECT_NEAR(odo->pose().x, 50 * kMetersPerCount, 1e-12);
}

TEST(WheelOdometry, StaleOrRepeatedSetIsIgnored) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading a[2] = {at(0, kStep), at(0, kStep)};
  const EncoderReading b[2] = {at(50, 2 * kStep), at(50, 2 * kStep)};
  const EncoderReading older[2] = {at(20, 0), at(20, 0)};
  EXPECT_FALSE(odo->update(a, 2, &tw));
  ASSERT_TRUE(odo->update(b, 2, &tw));
  EXPECT_FALSE(odo->update(b, 2, &tw));
  EXPECT_FALSE(odo->update(older, 2, &tw));
  EXPECT_EQ(odo->stats().stale, 2);
  const EncoderReading c[2] = {at(100, 3 * kStep), at(100, 3 * kStep)};
  ASSERT_TRUE(odo->update(c, 2, &tw));
  EXPECT_NEAR(tw.vx, kPi / 2, 1e-12);
}

TEST(WheelOdometry, BadInputIsCountedNotCrashed) {
  auto odo = make(diff_config());
  WheelTwist tw;
  const EncoderReading one[1] = {at(0, 0)};
  EXPECT_FALSE(odo->update(nullptr, 2, &tw));
  EXPECT_FALSE(odo->update(one, 1, &tw));  // the right wheel is encoder 1
  EXPECT_FALSE(odo->update(one, 1, nullptr));
  EXPECT_EQ(odo->stats().bad_input, 3);
  EXPECT_EQ(odo->stats().updates, 3);
}

TEST(WheelOdometry, ConfigErrorsNameTheField) {
  auto expect_error = [](const WheelOdometryConfig& c, const char* field) {
    std::string error;
    EXPECT_EQ(WheelOdometry::create(c, &error), nullptr);
    EXPECT_NE(error.find(field), std::string::npos) << error;
  };
  WheelOdometryConfig c = diff_config();
  c.track_width_m = 0.0;
  expect_error(c, "track_width_m = 0");
  c = diff_config();
  c.wheel_radius_m = std::nan("");
  expect_error(c, "wheel_radius_m = nan");
  c = diff_config();
  c.counts_per_rev = -4096;
  expect_error(c, "counts_per_rev = -4096");
  c = diff_config();
  c.gear_ratio = 0;
  expect_error(c, "gear_ratio = 0");
  c = diff_config();
  c.wheel_count = 1;
  expect_error(c, "wheel_count = 1");
  c = diff_config();
  c.wheels[1].side = WheelSide::kLeft;
  expect_error(c, "no right wheel");
  c = diff_config();
  c.wheels[1].sign = 2;
  expect_error(c, "wheels[1].sign = 2");
  c = diff_config();
  c.wheels[1].encoder_index = 8;
  expect_error(c, "wheels[1].encoder_index = 8");
  c = diff_config();
  c.wheels[1].encoder_index = 0;
  expect_error(c, "both use encoder_index 0");
  c = diff_config();
  c.skid_track_factor = 1.3;
  expect_error(c, "applies only to skid_steer");
  c = diff_config();
  c.kinematics = DriveKinematics::kSkidSteer;
  c.skid_track_factor = 0.9;
  expect_error(c, "skid_track_factor = 0.9");
  c = diff_config();
  c.slip_fraction = -0.1;
  expect_error(c, "slip_fraction -0.1");
  c = diff_config();
  c.max_gap_ns = 0;
  expect_error(c, "max_gap_ns = 0");
}

TEST(WheelOdometry, UpdateDoesNotAllocate) {
  auto odo = make(diff_config());
  WheelTwist tw;
  int outputs = 0;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 5000; ++i) {
    const bool valid = i % 97 != 50;  // an occasional invalid reading: re-seeds
    const EncoderReading r[2] = {at(i * 25, i * kStep, valid), at(i * 75, i * kStep)};
    outputs += odo->update(r, 2, &tw) ? 1 : 0;
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_GT(outputs, 4800);
}

TEST(PlanarPose, ArcMatchesTheCircleForAnyTurn) {
  for (double dyaw : {1e-9, 1e-5, 0.3, 2.0, -3.0}) {
    const double radius = 2.0;
    const PlanarPose p = rtfuse::drivers::integrate_arc({1.0, -1.0, 0.5}, radius * dyaw, dyaw);
    // Centre of the circle is to the left of the start heading.
    const double cx = 1.0 - radius * std::sin(0.5);
    const double cy = -1.0 + radius * std::cos(0.5);
    EXPECT_NEAR(p.x, cx + radius * std::sin(0.5 + dyaw), 1e-12) << dyaw;
    EXPECT_NEAR(p.y, cy - radius * std::cos(0.5 + dyaw), 1e-12) << dyaw;
    EXPECT_NEAR(p.yaw, rtfuse::drivers::wrap_angle(0.5 + dyaw), 1e-15) << dyaw;
  }
  EXPECT_NEAR(rtfuse::drivers::wrap_angle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(rtfuse::drivers::wrap_angle(-kPi), kPi, 1e-12);
}

TEST(WheelOdometry, FromCanopenNodesToAPose) {
  using rtfuse::sim::CanopenEncoderConfig;
  using rtfuse::sim::CanopenEncoderNode;
  using rtfuse::hal::mock::MockCanBus;
  MockCanBus bus;
  CanopenEncoderConfig lc;
  lc.node_id = 10;
  lc.speed_counts_per_s = 2500.0;  // pi/2 m/s with 1000 counts per wheel turn
  CanopenEncoderConfig rc = lc;
  rc.node_id = 11;
  rc.speed_counts_per_s = -2500.0;  // mirrored motor
  rc.position_width = 2;            // and a 16-bit counter that wraps every 26 s
  CanopenEncoderNode left(lc);
  CanopenEncoderNode right(rc);
  ASSERT_TRUE(bus.attach(left));
  ASSERT_TRUE(bus.attach(right));
  rtfuse::drivers::CanopenEncodersConfig ec;
  ec.node_count = 2;
  ec.nodes[0].node_id = 10;
  ec.nodes[1].node_id = 11;
  ec.nodes[1].tpdo.width_bits = 16;
  ec.max_counts_per_s = 10'000.0;
  std::string error;
  auto enc = rtfuse::drivers::CanopenEncoders::create(bus, ec, &error);
  ASSERT_NE(enc, nullptr) << error;
  WheelOdometryConfig wc = diff_config();
  wc.wheels[1].sign = -1;
  auto odo = make(wc);
  ASSERT_TRUE(enc->start(0));

  rtfuse::drivers::EncoderSampleSet set;
  WheelTwist tw;
  TimeNs first_stamp = -1;
  int outputs = 0;
  rtfuse::test::AllocScope scope;
  for (TimeNs t = 5 * kMs; t <= 30'000 * kMs; t += 5 * kMs) {  // 30 s: the 16-bit counter wraps
    bus.set_time(t);
    enc->poll(t);
    if (!enc->take_sample_set(&set)) continue;
    if (first_stamp < 0) first_stamp = set.stamp;
    if (odo->update(set.readings, set.node_count, &tw)) {
      ++outputs;
      ASSERT_NEAR(tw.vx, kPi / 2, 1.01 * kMetersPerCount / 0.005) << "within one count per period";
      ASSERT_NEAR(tw.vyaw, 0.0, 2.02 * kMetersPerCount / 0.005 / 0.5);
    }
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(outputs, 5998);
  // 2500 counts/s from the first sample on, within one count.
  const double expect_x = 2500.0 * rtfuse::ns_to_sec(odo->pose_stamp() - first_stamp) * kMetersPerCount;
  EXPECT_NEAR(odo->pose().x, expect_x, kMetersPerCount);
  // Left and right counters step 12/13 counts out of phase, so the heading
  // dithers by one count over the track; the drift stays inside that.
  const double one_count_yaw = kMetersPerCount / 0.5;
  EXPECT_LT(std::fabs(odo->pose().yaw), 1.01 * one_count_yaw);
  EXPECT_LT(std::fabs(odo->pose().y), expect_x * one_count_yaw);
}

}  // namespace wheel_odometry_test
