// Ground truth of the bus-level simulator: the planned motion does what the
// segments say, within the limits, and the wheel distances are the exact
// integrals of it (plus slip).
#include "sim/truth_trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rtfuse/odometry_t.hpp"
#include "sim/ground_truth.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::sim {
namespace truth_trajectory_test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

PathSegment straight(double length, double speed) {
  PathSegment g;
  g.type = SegmentType::kStraight;
  g.length_m = length;
  g.speed_mps = speed;
  return g;
}

PathSegment arc(double radius, double angle_deg, double speed) {
  PathSegment g;
  g.type = SegmentType::kArc;
  g.radius_m = radius;
  g.angle_rad = angle_deg * kDeg;
  g.speed_mps = speed;
  return g;
}

PathSegment spin(double angle_deg, double rate_dps) {
  PathSegment g;
  g.type = SegmentType::kSpin;
  g.angle_rad = angle_deg * kDeg;
  g.yaw_rate_rad_s = rate_dps * kDeg;
  return g;
}

PathSegment figure_eight(double radius, int laps, double speed, bool right_first = false) {
  PathSegment g;
  g.type = SegmentType::kFigureEight;
  g.radius_m = radius;
  g.laps = laps;
  g.speed_mps = speed;
  g.right_first = right_first;
  return g;
}

PathSegment stop(double duration) {
  PathSegment g;
  g.type = SegmentType::kStop;
  g.duration_s = duration;
  return g;
}

DriveScenario scenario(std::vector<PathSegment> path) {
  DriveScenario sc;
  sc.path = std::move(path);
  sc.limits.max_accel_mps2 = 0.5;
  sc.limits.max_yaw_accel_rad_s2 = 90.0 * kDeg;
  sc.robot.track_width_m = 0.5;
  sc.robot.wheel_count = 2;
  sc.robot.wheels[0] = SimWheel{1, true, 0.0};
  sc.robot.wheels[1] = SimWheel{2, false, 0.0};
  return sc;
}

TEST(TruthTrajectory, StraightLineCoversItsLengthWithinTheAccelerationLimit) {
  const TruthTrajectory truth(scenario({straight(10.0, 1.0)}));
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  // 2 s up to 1 m/s (1 m), 8 m at 1 m/s, 2 s down (1 m).
  EXPECT_NEAR(truth.plan().end_time(), 12.0, 1e-12);
  const TruthState up = truth.truth_at(1.0);
  EXPECT_NEAR(up.speed, 0.5, 1e-12);
  EXPECT_EQ(up.accel_body[0], 0.5);
  EXPECT_NEAR(up.x, 0.25, 1e-12);
  const TruthState cruise = truth.truth_at(6.0);
  EXPECT_NEAR(cruise.speed, 1.0, 1e-12);
  EXPECT_EQ(cruise.accel_body[0], 0.0);
  EXPECT_NEAR(cruise.x, 5.0, 1e-12);
  const TruthState down = truth.truth_at(11.0);
  EXPECT_NEAR(down.speed, 0.5, 1e-12);
  EXPECT_EQ(down.accel_body[0], -0.5);
  const TruthState end = truth.truth_at(12.0);
  EXPECT_NEAR(end.x, 10.0, 1e-12);
  EXPECT_EQ(end.y, 0.0);
  EXPECT_EQ(end.yaw, 0.0);
  EXPECT_EQ(end.speed, 0.0);
  EXPECT_NEAR(end.distance, 10.0, 1e-12);
  // After the drive: at rest where it ended; before it: at the origin.
  const TruthState later = truth.truth_at(100.0);
  EXPECT_EQ(later.x, end.x);
  EXPECT_EQ(later.speed, 0.0);
  const TruthState before = truth.truth_at(-1.0);
  EXPECT_EQ(before.x, 0.0);
  EXPECT_EQ(before.speed, 0.0);
}

TEST(TruthTrajectory, ArcFromRestHasItsRadiusAndTurnsItsAngle) {
  const TruthTrajectory truth(scenario({arc(2.0, 90.0, 1.0)}));
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  const TruthState end = truth.truth_at(truth.plan().end_time());
  // A quarter circle of radius 2 to the left: centre (0, 2).
  EXPECT_NEAR(end.x, 2.0, 1e-9);
  EXPECT_NEAR(end.y, 2.0, 1e-9);
  EXPECT_NEAR(end.yaw, 0.5 * kPi, 1e-12);
  for (double t = 0.1; t < truth.plan().end_time(); t += 0.1) {
    const TruthState s = truth.truth_at(t);
    EXPECT_NEAR(std::hypot(s.x, s.y - 2.0), 2.0, 1e-9) << t;
    EXPECT_NEAR(s.yaw_rate, s.speed / 2.0, 1e-12) << t;
    EXPECT_NEAR(s.accel_body[1], s.speed * s.speed / 2.0, 1e-12) << t;  // centripetal, to the left
  }
}

TEST(TruthTrajectory, ArcsBetweenStraightsTurnExactlyTheirAnglesThroughClothoids) {
  const TruthTrajectory truth(scenario({straight(3.0, 1.0), arc(1.5, 90.0, 1.0), arc(2.0, -30.0, 0.8),
                                        straight(3.0, 1.0)}));
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  EXPECT_NEAR(truth.plan().final_heading(), 60.0 * kDeg, 1e-12);
  // In the middle of the first arc the curvature is the arc's, and the yaw
  // rate never steps: straight -> arc goes through a clothoid.
  double max_curvature = 0.0;
  double prev_rate = 0.0;
  const double dt = 1e-3;
  for (double t = dt; t < truth.plan().end_time(); t += dt) {
    const TruthState s = truth.truth_at(t);
    if (s.speed > 0.1) max_curvature = std::max(max_curvature, std::abs(s.yaw_rate / s.speed));
    EXPECT_LT(std::abs(s.yaw_rate - prev_rate), 2.0 * dt) << t;
    prev_rate = s.yaw_rate;
  }
  EXPECT_NEAR(max_curvature, 1.0 / 1.5, 1e-6);
}

TEST(TruthTrajectory, FigureEightClosesAndTurnsNoTighterThanItsRadius) {
  const TruthTrajectory truth(scenario({straight(2.0, 1.0), figure_eight(2.0, 2, 1.0), straight(2.0, 1.0)}));
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  const TruthState end = truth.truth_at(truth.plan().end_time());
  EXPECT_NEAR(end.x, 4.0, 1e-9);
  EXPECT_NEAR(end.y, 0.0, 1e-9);
  EXPECT_NEAR(end.yaw, 0.0, 1e-12);
  double max_curvature = 0.0;
  double min_y = 0.0, max_y = 0.0;
  for (double t = 0.0; t < truth.plan().end_time(); t += 0.01) {
    const TruthState s = truth.truth_at(t);
    if (s.speed > 0.1) max_curvature = std::max(max_curvature, std::abs(s.yaw_rate / s.speed));
    min_y = std::min(min_y, s.y);
    max_y = std::max(max_y, s.y);
  }
  EXPECT_NEAR(max_curvature, 0.5, 1e-4);
  // Left lobe first, then the right one: it goes well to both sides.
  EXPECT_GT(max_y, 2.0);
  EXPECT_LT(min_y, -2.0);
  // Path length: laps * 2 pi * j0 * radius, plus the straights.
  EXPECT_NEAR(end.distance, 4.0 + 2 * 2.0 * kPi * 2.404825557695773 * 2.0, 1e-9);
}

TEST(TruthTrajectory, SpinTurnsInPlaceWithinTheYawAccelerationLimit) {
  const TruthTrajectory truth(scenario({straight(1.0, 0.5), spin(-270.0, 60.0), straight(1.0, 0.5)}));
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  const TruthState end = truth.truth_at(truth.plan().end_time());
  EXPECT_NEAR(end.heading, -270.0 * kDeg, 1e-12);
  EXPECT_NEAR(end.x, 1.0, 1e-12);
  EXPECT_NEAR(end.y, 1.0, 1e-12);  // the second metre after turning to +90 degrees
  double peak = 0.0;
  for (double t = 0.0; t < truth.plan().end_time(); t += 0.01) {
    const TruthState s = truth.truth_at(t);
    peak = std::max(peak, std::abs(s.yaw_rate));
    EXPECT_LE(std::abs(s.yaw_accel), 90.0 * kDeg + 1e-12) << t;
    if (s.yaw_rate != 0.0) {
      EXPECT_EQ(s.speed, 0.0) << t;  // in place
    }
  }
  EXPECT_NEAR(peak, 60.0 * kDeg, 1e-9);
}

TEST(TruthTrajectory, LimitsHoldAndTheStateIsItsOwnDerivative) {
  DriveScenario sc;
  std::string error;
  ASSERT_TRUE(load_drive_scenario(RTFUSE_SOURCE_DIR "/config/scenarios/demo.toml", &sc, &error)) << error;
  const TruthTrajectory truth(sc);
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  const double a_max = sc.limits.max_accel_mps2;
  // On an arc the yaw rate follows the speed (v / r), so accelerating on it
  // adds a_max / r to the clothoids' and spins' limit.
  const double yaw_accel_max = sc.limits.max_yaw_accel_rad_s2 + truth.plan().max_curvature() * a_max;
  const double dt = 1e-3;
  TruthState prev = truth.truth_at(0.0);
  int checked = 0;
  for (double t = dt; t <= truth.plan().end_time(); t += dt) {
    const TruthState s = truth.truth_at(t);
    ASSERT_LE(std::abs(s.accel_body[0]), a_max) << t;
    ASSERT_LE(std::abs(s.yaw_accel), yaw_accel_max + 1e-9) << t;
    ASSERT_LE(std::abs(s.speed - prev.speed), a_max * dt + 1e-12) << t;
    ASSERT_LE(std::abs(s.yaw_rate - prev.yaw_rate), yaw_accel_max * dt + 1e-9) << t;
    // Finite differences against the state's own rates (a kink where an
    // acceleration phase starts costs up to a_max * dt / 8).
    const double v = 0.5 * (s.speed + prev.speed);
    const double psi = 0.5 * (s.heading + prev.heading);
    ASSERT_NEAR((s.x - prev.x) / dt, v * std::cos(psi), 1e-4) << t;
    ASSERT_NEAR((s.y - prev.y) / dt, v * std::sin(psi), 1e-4) << t;
    ASSERT_NEAR((s.heading - prev.heading) / dt, 0.5 * (s.yaw_rate + prev.yaw_rate), yaw_accel_max * dt / 4.0) << t;
    ASSERT_NEAR((s.distance - prev.distance) / dt, v, 1e-4) << t;
    ASSERT_GE(s.speed, 0.0);
    prev = s;
    ++checked;
  }
  EXPECT_GT(checked, 100'000);
}

TEST(TruthTrajectory, WheelDistancesAreTheIntegralsOfTheKinematics) {
  DriveScenario sc = scenario({straight(2.0, 1.0), arc(1.0, 120.0, 0.8), spin(90.0, 45.0), figure_eight(1.0, 1, 0.6)});
  const TruthTrajectory truth(sc);
  ASSERT_TRUE(truth.valid()) << truth.problem().message;
  const double half_track = 0.25;
  double left = 0.0, right = 0.0;
  const double dt = 1e-3;
  TruthState prev = truth.truth_at(0.0);
  for (double t = dt; t <= truth.plan().end_time() + 1.0; t += dt) {
    const TruthState s = truth.truth_at(t);
    // Trapezoid of v -/+ yaw_rate * track / 2.
    left += 0.5 * dt * ((prev.speed - half_track * prev.yaw_rate) + (s.speed - half_track * s.yaw_rate));
    right += 0.5 * dt * ((prev.speed + half_track * prev.yaw_rate) + (s.speed + half_track * s.yaw_rate));
    ASSERT_NEAR(s.wheel_distance[0], left, 1e-5) << t;
    ASSERT_NEAR(s.wheel_distance[1], right, 1e-5) << t;
    // And exactly: the path length -/+ the heading change times half the track.
    ASSERT_DOUBLE_EQ(s.wheel_distance[0], s.distance - half_track * s.heading) << t;
    ASSERT_DOUBLE_EQ(s.wheel_distance[1], s.distance + half_track * s.heading) << t;
    prev = s;
  }
  // The spin alone: the wheels rolled opposite ways by a quarter turn of the track circle.
  EXPECT_NEAR(prev.wheel_distance[1] - prev.wheel_distance[0], 0.5 * (120.0 + 90.0) * kDeg, 1e-9);
}

TEST(TruthTrajectory, SlipEpisodeAddsItsFractionOfTheDistanceToItsWheelsOnly) {
  DriveScenario sc = scenario({straight(20.0, 1.2)});
  sc.robot.kinematics = DriveKinematics::kSkidSteer;
  sc.robot.wheel_count = 4;
  sc.robot.wheels = {SimWheel{1, true, 0.0}, SimWheel{3, true, 0.0}, SimWheel{2, false, 0.0}, SimWheel{4, false, 0.0}};
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{6.0, 2.0, 0x03, 0.3};  // both left wheels, at cruise speed
  const TruthTrajectory truth(sc);
  ASSERT_TRUE(truth.valid());
  const TruthState mid = truth.truth_at(7.0);
  EXPECT_NEAR(mid.wheel_distance[0] - mid.distance, 0.3 * 1.2 * 1.0, 1e-9);
  EXPECT_EQ(mid.wheel_slip[0], 0.3);
  EXPECT_EQ(mid.wheel_slip[2], 0.0);
  const TruthState after = truth.truth_at(12.0);
  EXPECT_NEAR(after.wheel_distance[0] - after.distance, 0.3 * 1.2 * 2.0, 1e-9);
  EXPECT_NEAR(after.wheel_distance[1] - after.distance, 0.3 * 1.2 * 2.0, 1e-9);
  EXPECT_EQ(after.wheel_distance[2], after.distance);
  EXPECT_EQ(after.wheel_distance[3], after.distance);
  EXPECT_EQ(after.wheel_slip[0], 0.0);
  // The robot itself went straight on.
  EXPECT_EQ(after.y, 0.0);
  EXPECT_EQ(after.yaw, 0.0);
}

TEST(TruthTrajectory, ContinuousSlipHasItsSpreadAndIsTheSameForTheSameSeed) {
  DriveScenario sc = scenario({straight(600.0, 1.0)});
  sc.slip.noise_fraction = 0.02;
  sc.slip.correlation_time_s = 0.5;
  sc.seed = 7;
  const TruthTrajectory a(sc);
  const TruthTrajectory b(sc);
  sc.seed = 8;
  const TruthTrajectory c(sc);
  double sum = 0.0, sum_sq = 0.0;
  int n = 0;
  int differ = 0;
  for (double t = 0.0; t < 600.0; t += 0.25) {
    const TruthState sa = a.truth_at(t);
    const TruthState sb = b.truth_at(t);
    ASSERT_EQ(sa.wheel_slip[0], sb.wheel_slip[0]);
    ASSERT_EQ(sa.wheel_distance[1], sb.wheel_distance[1]);
    differ += sa.wheel_slip[0] != c.truth_at(t).wheel_slip[0];
    sum += sa.wheel_slip[0];
    sum_sq += sa.wheel_slip[0] * sa.wheel_slip[0];
    ++n;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum_sq / n - mean * mean);
  // ~1200 samples 0.5 correlation times apart: the spread within 15 %.
  EXPECT_NEAR(sd, 0.02, 0.003);
  EXPECT_LT(std::abs(mean), 0.003);
  EXPECT_GT(differ, n - 5);
  // The slip distance is the integral of speed times slip, and the wheels differ.
  const TruthState end = a.truth_at(600.0);
  EXPECT_NE(end.wheel_distance[0], end.wheel_distance[1]);
  EXPECT_LT(std::abs(end.wheel_distance[0] - end.distance), 0.02 * 600.0);
  double integral = 0.0;
  const double dt = 0.001;
  for (double t = 0.0; t < 20.0; t += dt) {
    const TruthState mid = a.truth_at(t + 0.5 * dt);
    integral += dt * mid.speed * mid.wheel_slip[0];
  }
  const TruthState at20 = a.truth_at(20.0);
  EXPECT_NEAR(at20.wheel_distance[0] - at20.distance, integral, 1e-4);
}

TEST(TruthTrajectory, AScenarioThatCannotBeDrivenLeavesTheRobotAtRest) {
  // 90 degrees at 0.5 m radius and 1 m/s: the clothoids alone turn 146.
  const TruthTrajectory truth(scenario({straight(2.0, 1.0), arc(0.5, 90.0, 1.0), straight(2.0, 1.0)}));
  EXPECT_FALSE(truth.valid());
  EXPECT_EQ(truth.problem().segment, 1);
  EXPECT_NE(truth.problem().message.find("145.9 deg"), std::string::npos) << truth.problem().message;
  const TruthState s = truth.truth_at(3.0);
  EXPECT_EQ(s.x, 0.0);
  EXPECT_EQ(s.speed, 0.0);
  EXPECT_EQ(s.wheel_distance[0], 0.0);
  // And garbage time gives the start, not NaN.
  const TruthState n = TruthTrajectory(scenario({straight(2.0, 1.0)})).truth_at(std::nan(""));
  EXPECT_EQ(n.x, 0.0);
  EXPECT_EQ(n.wheel_distance[1], 0.0);
}

TEST(TruthTrajectory, LookupsDoNotAllocate) {
  DriveScenario sc = scenario(
      {straight(2.0, 1.0), arc(1.0, 90.0, 0.8), stop(1.0), spin(90.0, 45.0), figure_eight(1.0, 1, 0.6)});
  sc.slip.noise_fraction = 0.01;
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{1.0, 2.0, 0x01, 0.2};
  const TruthTrajectory truth(sc);
  rtfuse::odometry_t msg;
  fill_ground_truth(truth.truth_at(0.0), 0, 0, &msg);
  double sink = 0.0;
  {
    rtfuse::test::AllocScope scope;
    for (double t = -1.0; t < truth.plan().end_time() + 1.0; t += 0.01) {
      const TruthState s = truth.truth_at(t);
      fill_ground_truth(s, sec_to_ns(t), 1, &msg);
      sink += s.x + s.wheel_distance[0] + msg.pose.pose.orientation.z;
    }
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(TruthTrajectory, GroundTruthMessageCarriesThePoseAndTwist) {
  const TruthTrajectory truth(scenario({arc(2.0, 135.0, 1.0)}));
  const TruthState s = truth.truth_at(3.0);
  rtfuse::odometry_t msg;
  msg.pose.covariance[7] = 5.0;
  fill_ground_truth(s, 1'234'567'891, 42, &msg);
  EXPECT_EQ(msg.header.utime, 1'234'567);
  EXPECT_EQ(msg.header.seq, 42);
  EXPECT_EQ(msg.header.frame_id, "odom");
  EXPECT_EQ(msg.child_frame_id, "base_link");
  EXPECT_EQ(std::string(kGroundTruthChannel), "sim/ground_truth");
  EXPECT_EQ(msg.pose.pose.position.x, s.x);
  EXPECT_EQ(msg.pose.pose.position.y, s.y);
  EXPECT_NEAR(2.0 * std::atan2(msg.pose.pose.orientation.z, msg.pose.pose.orientation.w), s.yaw, 1e-12);
  EXPECT_EQ(msg.twist.twist.linear.x, s.speed);
  EXPECT_EQ(msg.twist.twist.angular.z, s.yaw_rate);
  EXPECT_GT(s.yaw_rate, 0.1);
  EXPECT_EQ(msg.pose.covariance[7], 0.0);
}

}  // namespace truth_trajectory_test
}  // namespace rtfuse::sim
