#include "sim/sim_lcm_robot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "geometry/rotation.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "support/alloc_counter.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::sim {
namespace sim_lcm_robot_test {

constexpr TimeNs kSec = 1'000'000'000;
constexpr TimeNs kStart = 1'000 * kSec;  // a monotonic clock is rarely near 0
constexpr double kPi = 3.14159265358979323846;

struct Captured {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  TimeNs stamp;
};

std::vector<Captured> drain(SimLcmRobot& robot, TimeNs until) {
  std::vector<Captured> out;
  SimMessage m{};
  while (robot.next_due(until, &m)) out.push_back({m.channel, {m.data, m.data + m.size}, m.stamp});
  return out;
}

template <class Msg>
Msg decode(const Captured& c) {
  Msg m;
  EXPECT_EQ(m.decode(c.bytes.data(), 0, static_cast<int>(c.bytes.size())), static_cast<int>(c.bytes.size()));
  return m;
}

double yaw_of(const rtfuse::quaternion_t& q) {
  return geometry::rpy_from_quaternion(Eigen::Quaterniond(q.w, q.x, q.y, q.z)).z();
}

double angle_diff(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

struct Stats {
  double sum = 0.0, sum_sq = 0.0;
  int n = 0;
  void add(double x) {
    sum += x;
    sum_sq += x * x;
    ++n;
  }
  double mean() const { return sum / n; }
  double stddev() const { return std::sqrt(sum_sq / n - mean() * mean()); }
};

TEST(SimLcmRobot, MessageRatesOverTenSeconds) {
  SimLcmRobot robot(SimLcmConfig{}, kStart);
  const auto msgs = drain(robot, kStart + 10 * kSec - 1);
  int imu = 0, odom = 0, truth = 0;
  for (const auto& m : msgs) {
    imu += m.channel == "imu/data";
    odom += m.channel == "wheel/odom";
    truth += m.channel == "sim/ground_truth";
  }
  EXPECT_NEAR(imu, 1000, 1);
  EXPECT_NEAR(odom, 500, 1);
  EXPECT_NEAR(truth, 500, 1);
  EXPECT_EQ(imu + odom + truth, static_cast<int>(msgs.size()));
}

TEST(SimLcmRobot, MessagesComeInTimeOrderWithMatchingHeaders) {
  SimLcmRobot robot(SimLcmConfig{}, kStart);
  EXPECT_EQ(robot.next_time(), kStart);
  SimMessage m{};
  EXPECT_FALSE(robot.next_due(kStart - 1, &m));  // nothing before its time

  TimeNs previous = 0;
  int imu_seq = 0, odom_seq = 0;
  for (int i = 0; i < 2000; ++i) {
    const TimeNs expected = robot.next_time();
    ASSERT_TRUE(robot.next_due(kStart + 20 * kSec, &m));
    ASSERT_EQ(m.stamp, expected);
    ASSERT_GE(m.stamp, previous);
    previous = m.stamp;
    const Captured c{m.channel, {m.data, m.data + m.size}, m.stamp};
    if (c.channel == "imu/data") {
      const auto imu = decode<rtfuse::imu_t>(c);
      EXPECT_EQ(imu.header.utime, ns_to_utime(m.stamp));
      EXPECT_EQ(imu.header.seq, imu_seq++);
      EXPECT_EQ(imu.header.frame_id, "base_link");
    } else {
      const auto odom = decode<rtfuse::odometry_t>(c);
      EXPECT_EQ(odom.header.utime, ns_to_utime(m.stamp));
      EXPECT_EQ(odom.header.frame_id, "odom");
      EXPECT_EQ(odom.child_frame_id, "base_link");
      if (c.channel == "wheel/odom") {
        EXPECT_EQ(odom.header.seq, odom_seq++);
      }
    }
  }
}

TEST(SimLcmRobot, TruthIsAFigureEightThatClosesAfterOnePeriod) {
  SimLcmConfig cfg;
  SimLcmRobot robot(cfg, kStart);
  const double period = robot.period_s();
  ASSERT_TRUE(std::isfinite(period));

  const TruthPose p0 = robot.truth(kStart);
  EXPECT_NEAR(p0.x, 0.0, 1e-12);
  EXPECT_NEAR(p0.y, 0.0, 1e-12);
  EXPECT_NEAR(p0.yaw, 0.0, 1e-12);  // starts facing +x, like an odom frame
  const TruthPose p1 = robot.truth(kStart + sec_to_ns(period));
  EXPECT_NEAR(p1.x, 0.0, 1e-6);
  EXPECT_NEAR(p1.y, 0.0, 1e-6);
  EXPECT_NEAR(angle_diff(p1.yaw, 0.0), 0.0, 1e-6);

  // Sample one period as a polyline: its length gives the mean speed, and two
  // non-adjacent segments must cross (an oval would not).
  const int n = 2000;
  std::vector<TruthPose> pts;
  for (int i = 0; i <= n; ++i) pts.push_back(robot.truth(kStart + sec_to_ns(period * i / n)));
  double length = 0.0, max_extent = 0.0;
  for (int i = 1; i <= n; ++i) {
    length += std::hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y);
    max_extent = std::max(max_extent, std::hypot(pts[i].x, pts[i].y));
  }
  EXPECT_NEAR(length / period, cfg.speed_mps, 0.01 * cfg.speed_mps);
  EXPECT_GT(max_extent, 1.5 * cfg.figure_eight_radius_m);  // each lobe ~2r long

  auto cross = [](double ax, double ay, double bx, double by, double cx, double cy) {
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  };
  int crossings = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // the closing joint, not a crossing
      const auto &a = pts[i], &b = pts[i + 1], &c = pts[j], &d = pts[j + 1];
      const double d1 = cross(a.x, a.y, b.x, b.y, c.x, c.y), d2 = cross(a.x, a.y, b.x, b.y, d.x, d.y);
      const double d3 = cross(c.x, c.y, d.x, d.y, a.x, a.y), d4 = cross(c.x, c.y, d.x, d.y, b.x, b.y);
      if (d1 * d2 < 0 && d3 * d4 < 0) ++crossings;
    }
  }
  EXPECT_GE(crossings, 1);

  // Heading, speed and yaw rate are the analytic derivatives of the path.
  for (int i = 1; i < n; i += 37) {
    const double dt = period / n;
    const auto &a = pts[i - 1], &b = pts[i + 1];
    const TruthPose& p = pts[i];
    EXPECT_NEAR(std::hypot(b.x - a.x, b.y - a.y) / (2 * dt), p.vx, 1e-3) << i;
    EXPECT_NEAR(angle_diff(std::atan2(b.y - a.y, b.x - a.x), p.yaw), 0.0, 1e-3) << i;
    EXPECT_NEAR(angle_diff(b.yaw, a.yaw) / (2 * dt), p.vyaw, 1e-3) << i;
  }
}

TEST(SimLcmRobot, ImuMatchesTruthPlusBiasWithinNoise) {
  SimLcmConfig cfg;
  SimLcmRobot robot(cfg, kStart);
  const SimBiases& bias = robot.biases();
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(std::abs(bias.gyro[i]), cfg.gyro_bias_rad_s);
    EXPECT_EQ(std::abs(bias.accel[i]), cfg.accel_bias_mps2);
  }

  Stats wx, wz, ax, ay, az, yaw;
  for (const auto& c : drain(robot, kStart + 10 * kSec - 1)) {
    if (c.channel != "imu/data") continue;
    const auto imu = decode<rtfuse::imu_t>(c);
    const TruthPose truth = robot.truth(c.stamp);
    const double t = ns_to_sec(c.stamp - kStart);
    wx.add(imu.angular_velocity.x);
    wz.add(imu.angular_velocity.z - truth.vyaw);
    az.add(imu.linear_acceleration.z);
    ay.add(imu.linear_acceleration.y - truth.vx * truth.vyaw);
    // Forward acceleration by differentiating the truth speed.
    const TimeNs h = 1'000'000;
    const double accel = (robot.truth(c.stamp + h).vx - robot.truth(c.stamp - h).vx) / 2e-3;
    ax.add(imu.linear_acceleration.x - accel);
    yaw.add(angle_diff(yaw_of(imu.orientation), truth.yaw));
    (void)t;

    EXPECT_EQ(imu.angular_velocity_covariance[8], cfg.gyro_noise_rad_s * cfg.gyro_noise_rad_s);
    EXPECT_EQ(imu.linear_acceleration_covariance[0], cfg.accel_noise_mps2 * cfg.accel_noise_mps2);
    EXPECT_EQ(imu.orientation_covariance[1], 0.0);
    // The yaw variance owns up to the AHRS's wandering error, not just white noise.
    EXPECT_NEAR(imu.orientation_covariance[8],
                cfg.orientation_noise_rad * cfg.orientation_noise_rad + cfg.yaw_error_rad * cfg.yaw_error_rad, 1e-15);
  }
  ASSERT_EQ(wz.n, 1000);
  // Means within 5 standard errors, spreads within 15 % of the configured noise.
  const double gyro_se = 5 * cfg.gyro_noise_rad_s / std::sqrt(wz.n);
  const double accel_se = 5 * cfg.accel_noise_mps2 / std::sqrt(ax.n);
  EXPECT_NEAR(wz.mean(), bias.gyro[2], gyro_se);
  EXPECT_NEAR(wx.mean(), bias.gyro[0], gyro_se);
  EXPECT_NEAR(wz.stddev(), cfg.gyro_noise_rad_s, 0.15 * cfg.gyro_noise_rad_s);
  EXPECT_NEAR(ax.mean(), bias.accel[0], accel_se);
  EXPECT_NEAR(ay.mean(), bias.accel[1], accel_se);
  EXPECT_NEAR(az.mean(), 9.80665 + bias.accel[2], accel_se);
  EXPECT_NEAR(az.stddev(), cfg.accel_noise_mps2, 0.15 * cfg.accel_noise_mps2);
  // Over 10 s the 30 s-correlated error barely moves: its mean is one draw.
  EXPECT_LT(std::abs(yaw.mean()), 4 * cfg.yaw_error_rad);
  EXPECT_GT(yaw.stddev(), 0.85 * cfg.orientation_noise_rad);
  EXPECT_LT(yaw.stddev(), std::hypot(cfg.orientation_noise_rad, cfg.yaw_error_rad));
}

TEST(SimLcmRobot, ImuYawErrorStaysBoundedOverALongDrive) {
  SimLcmConfig cfg;
  cfg.imu_rate_hz = 20.0;  // fewer messages, same error process
  SimLcmRobot robot(cfg, kStart);
  Stats yaw;
  double worst = 0.0;
  for (const auto& c : drain(robot, kStart + 1200 * kSec)) {
    if (c.channel != "imu/data") continue;
    const double e = angle_diff(yaw_of(decode<rtfuse::imu_t>(c).orientation), robot.truth(c.stamp).yaw);
    yaw.add(e);
    worst = std::max(worst, std::abs(e));
  }
  const double sigma = std::hypot(cfg.orientation_noise_rad, cfg.yaw_error_rad);
  // 20 minutes = 40 correlation times: a drifting error would be far beyond these.
  EXPECT_NEAR(yaw.stddev(), sigma, 0.35 * sigma);
  EXPECT_LT(std::abs(yaw.mean()), sigma);
  EXPECT_LT(worst, 5.5 * sigma);
}

TEST(SimLcmRobot, OdometryTwistIsSlippedTruthPlusNoise) {
  SimLcmConfig cfg;
  SimLcmRobot robot(cfg, kStart);
  Stats vx, vyaw;
  double slip_min = 1.0, slip_max = -1.0, yaw_error_max = 0.0, final_error = 0.0;
  for (const auto& c : drain(robot, kStart + 20 * kSec - 1)) {
    if (c.channel != "wheel/odom") continue;
    const auto odom = decode<rtfuse::odometry_t>(c);
    const TruthPose truth = robot.truth(c.stamp);
    const LcmSimRobotSlip s = robot.slip(c.stamp);
    slip_min = std::min({slip_min, s.left, s.right, s.speed_fraction});
    slip_max = std::max({slip_max, s.left, s.right, s.speed_fraction});
    yaw_error_max = std::max(yaw_error_max, std::abs(s.yaw_rate_error));
    vx.add(odom.twist.twist.linear.x - truth.vx * (1 + s.speed_fraction));
    vyaw.add(odom.twist.twist.angular.z - (truth.vyaw + s.yaw_rate_error));
    EXPECT_EQ(odom.twist.twist.linear.y, 0.0);
    EXPECT_EQ(odom.twist.covariance[0], cfg.odom_speed_noise_mps * cfg.odom_speed_noise_mps);
    EXPECT_EQ(odom.twist.covariance[7], 1e-4);  // vy: the non-holonomic claim
    EXPECT_EQ(odom.twist.covariance[35], cfg.odom_yaw_rate_noise_rad_s * cfg.odom_yaw_rate_noise_rad_s);
    EXPECT_EQ(odom.twist.covariance[1], 0.0);
    EXPECT_EQ(odom.pose.covariance[0], 1e3);
    EXPECT_EQ(odom.pose.covariance[35], 1e3);
    final_error = std::hypot(odom.pose.pose.position.x - truth.x, odom.pose.pose.position.y - truth.y);
  }
  ASSERT_EQ(vx.n, 1000);
  EXPECT_NEAR(vx.mean(), 0.0, 5 * cfg.odom_speed_noise_mps / std::sqrt(vx.n));
  EXPECT_NEAR(vx.stddev(), cfg.odom_speed_noise_mps, 0.15 * cfg.odom_speed_noise_mps);
  EXPECT_NEAR(vyaw.mean(), 0.0, 5 * cfg.odom_yaw_rate_noise_rad_s / std::sqrt(vyaw.n));
  EXPECT_NEAR(vyaw.stddev(), cfg.odom_yaw_rate_noise_rad_s, 0.15 * cfg.odom_yaw_rate_noise_rad_s);
  // Slip is bounded, and actually varies over 20 s. One wheel slipping more
  // than the other shows up as a yaw-rate error: the weak point of wheel odometry.
  EXPECT_LE(slip_max, cfg.wheel_slip);
  EXPECT_GE(slip_min, -cfg.wheel_slip);
  EXPECT_GT(slip_max - slip_min, 0.5 * cfg.wheel_slip);
  EXPECT_GT(yaw_error_max, cfg.odom_yaw_rate_noise_rad_s);
  // Dead reckoning drifts, but over 20 s (~20 m) it stays within a metre.
  EXPECT_GT(final_error, 0.0);
  EXPECT_LT(final_error, 1.0);
}

TEST(SimLcmRobot, SameSeedGivesIdenticalBytes) {
  SimLcmConfig cfg;
  cfg.seed = 42;
  SimLcmRobot a(cfg, kStart), b(cfg, kStart);
  const auto ma = drain(a, kStart + 5 * kSec);
  // b is drained in a different rhythm: the output must not depend on it.
  std::vector<Captured> mb;
  for (TimeNs t = kStart; t <= kStart + 5 * kSec; t += 7'300'000) {
    const auto part = drain(b, t);
    mb.insert(mb.end(), part.begin(), part.end());
  }
  const auto rest = drain(b, kStart + 5 * kSec);
  mb.insert(mb.end(), rest.begin(), rest.end());
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i) {
    ASSERT_EQ(ma[i].channel, mb[i].channel) << i;
    ASSERT_EQ(ma[i].stamp, mb[i].stamp) << i;
    ASSERT_EQ(ma[i].bytes, mb[i].bytes) << i;
  }

  cfg.seed = 43;
  SimLcmRobot c(cfg, kStart);
  const auto mc = drain(c, kStart + 5 * kSec);
  ASSERT_EQ(mc.size(), ma.size());
  int differing = 0;
  for (std::size_t i = 0; i < ma.size(); ++i) differing += ma[i].bytes != mc[i].bytes;
  EXPECT_GT(differing, static_cast<int>(ma.size()) / 2);
}

TEST(SimLcmRobot, NextDueNeverAllocates) {
  SimLcmRobot robot(SimLcmConfig{}, kStart);
  SimMessage m{};
  TimeNs now = kStart;
  for (; now < kStart + kSec; now += 5'000'000)
    while (robot.next_due(now, &m)) {
    }

  long messages = 0, empty = 0;
  std::size_t allocations = 0;
  {
    test::EigenMallocForbidden eigen_no_malloc;
    test::AllocScope scope;
    for (; now < kStart + 60 * kSec; now += 5'000'000) {
      while (robot.next_due(now, &m)) {
        ++messages;
        empty += m.size == 0;
      }
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(messages, 11000);
  EXPECT_EQ(empty, 0);  // every message was encoded

  // The counter is live in this executable.
  test::AllocScope probe;
  std::vector<Captured> kept = drain(robot, now + kSec);
  EXPECT_GT(probe.count(), 0u);
}

}  // namespace sim_lcm_robot_test
}  // namespace rtfuse::sim
