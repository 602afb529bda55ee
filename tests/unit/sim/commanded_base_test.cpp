// The commanded base (issue 28): velocity commands through the drive's
// kinematics, latency, limits and watchdog, integrated by each reader on
// its own; readers fed the same commands agree bit for bit, and what breaks
// that (a late command, a lapped feed) is counted.
#include "sim/commanded_base.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/config/config_loader.hpp"
#include "sim/sim_drive.hpp"
#include "sim/sim_imu.hpp"
#include "sim/sim_robot.hpp"
#include "support/alloc_counter.hpp"
#include "support/sim_toml.hpp"
#include "support/temp_file.hpp"

namespace rtfuse::sim {
namespace commanded_base_test {

constexpr TimeNs kT0 = 1'000'000'000;
constexpr TimeNs kMs = 1'000'000;
constexpr double kStep = 1e-3;

DriveScenario commanded_scenario() {
  DriveScenario sc;
  sc.mode = DriveMode::kCommanded;
  sc.duration_s = 120.0;
  sc.robot.track_width_m = 0.5;
  sc.robot.wheel_count = 2;
  sc.robot.wheels[0] = SimWheel{1, true, 0.0};
  sc.robot.wheels[1] = SimWheel{2, false, 0.0};
  return sc;  // [base] at its defaults: 1 m/s, 1 m/s^2, 20 ms, 0.5 s
}

// One feed and the slip every reader shares, as SimRobot makes them.
struct Base {
  explicit Base(const DriveScenario& s) : sc(s), slip(sc, sc.duration_s) {}
  std::unique_ptr<CommandedTruth> reader() const {
    return std::make_unique<CommandedTruth>(sc, slip, feed, kT0);
  }
  bool push(TimeNs since_start, double linear, double angular) {
    return feed.push(BaseCommand{kT0 + since_start, linear, angular});
  }
  DriveScenario sc;
  WheelSlipModel slip;
  CommandFeed feed;
};

TruthState at(CommandedTruth& r, TimeNs since_start) { return r.truth_at(ns_to_sec(since_start)); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every field, bit for bit (the struct has padding, so not one memcmp).
::testing::AssertionResult identical(const TruthState& a, const TruthState& b) {
  std::vector<std::pair<const char*, std::pair<double, double>>> f = {
      {"t", {a.t, b.t}},
      {"x", {a.x, b.x}},
      {"y", {a.y, b.y}},
      {"yaw", {a.yaw, b.yaw}},
      {"heading", {a.heading, b.heading}},
      {"speed", {a.speed, b.speed}},
      {"yaw_rate", {a.yaw_rate, b.yaw_rate}},
      {"yaw_accel", {a.yaw_accel, b.yaw_accel}},
      {"accel_x", {a.accel_body[0], b.accel_body[0]}},
      {"accel_y", {a.accel_body[1], b.accel_body[1]}},
      {"distance", {a.distance, b.distance}}};
  for (int w = 0; w < kMaxSimWheels; ++w) {
    f.push_back({"wheel_distance", {a.wheel_distance[w], b.wheel_distance[w]}});
    f.push_back({"wheel_slip", {a.wheel_slip[w], b.wheel_slip[w]}});
  }
  if (a.wheel_count != b.wheel_count) return ::testing::AssertionFailure() << "wheel_count";
  for (const auto& [name, v] : f) {
    if (!same_bits(v.first, v.second)) {
      return ::testing::AssertionFailure() << name << ": " << v.first << " vs " << v.second << " at t " << a.t;
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(CommandedBase, ConstantCommandDrivesACircleOfRadiusVOverW) {
  Base base(commanded_scenario());
  // A navigator's 10 Hz commands, all (0.5 m/s, 0.5 rad/s): radius 1 m.
  // Sides 0.375 and 0.625 m/s, reached 625 steps after the latency.
  for (TimeNs t = 0; t <= 30'000 * kMs; t += 100 * kMs) base.push(t, 0.5, 0.5);
  auto r = base.reader();
  const double radius = 0.5 / 0.5;
  const TruthState start = at(*r, 1000 * kMs);  // the ramp ended at 0.645 s
  EXPECT_EQ(start.speed, 0.5);
  EXPECT_EQ(start.yaw_rate, 0.5);
  EXPECT_EQ(start.accel_body[0], 0.0);
  EXPECT_EQ(start.accel_body[1], 0.25);  // v w, towards the centre
  const double cx = start.x - radius * std::sin(start.heading);
  const double cy = start.y + radius * std::cos(start.heading);
  for (TimeNs t = 1000 * kMs; t <= 30'000 * kMs; t += 7 * kMs + 123) {  // between steps too
    const TruthState s = at(*r, t);
    const double heading = start.heading + 0.5 * ns_to_sec(t - 1000 * kMs);
    ASSERT_NEAR(s.heading, heading, 1e-9) << ns_to_sec(t);
    ASSERT_NEAR(s.x, cx + radius * std::sin(heading), 1e-9) << ns_to_sec(t);
    ASSERT_NEAR(s.y, cy - radius * std::cos(heading), 1e-9) << ns_to_sec(t);
    ASSERT_NEAR(std::remainder(s.yaw - heading, 2.0 * M_PI), 0.0, 1e-9);
    ASSERT_EQ(s.speed, 0.5);
  }
  EXPECT_EQ(r->late_commands(), 0);
  EXPECT_EQ(r->watchdog_stops(), 0);

  // Straight ahead (w = 0) stays exactly on the line.
  Base straight(commanded_scenario());
  for (TimeNs t = 0; t <= 5000 * kMs; t += 100 * kMs) straight.push(t, 0.4, 0.0);
  auto line = straight.reader();
  for (TimeNs t = 0; t <= 5000 * kMs; t += 10 * kMs) {
    const TruthState s = at(*line, t);
    ASSERT_EQ(s.y, 0.0);
    ASSERT_EQ(s.heading, 0.0);
  }
  // 0.02 s latency, 0.4 s ramp (0.08 m), then 0.4 m/s.
  EXPECT_NEAR(at(*line, 5000 * kMs).x, 0.08 + 0.4 * (5.0 - 0.42), 1e-3);
}

TEST(CommandedBase, WheelSpeedsAreClampedToTheMaximum) {
  Base base(commanded_scenario());
  for (TimeNs t = 0; t <= 3000 * kMs; t += 100 * kMs) base.push(t, 5.0, 0.0);
  auto r = base.reader();
  const TruthState s2 = at(*r, 2000 * kMs);
  EXPECT_EQ(s2.speed, 1.0);  // max_wheel_speed_mps
  EXPECT_NEAR(at(*r, 3000 * kMs).wheel_distance[0] - s2.wheel_distance[0], 1.0, 1e-9);

  // Each side on its own: (1 m/s, 2 rad/s) asks 0.5 and 1.5 m/s; the right
  // side gives 1.0, so the base drives 0.75 m/s at 1 rad/s.
  Base turning(commanded_scenario());
  for (TimeNs t = 0; t <= 3000 * kMs; t += 100 * kMs) turning.push(t, 1.0, 2.0);
  auto q = turning.reader();
  const TruthState s = at(*q, 2500 * kMs);
  EXPECT_EQ(s.speed, 0.75);
  EXPECT_EQ(s.yaw_rate, 1.0);
}

TEST(CommandedBase, SpeedRampsAtTheWheelAcceleration) {
  DriveScenario sc = commanded_scenario();
  sc.base.max_wheel_accel_mps2 = 0.5;
  Base base(sc);
  for (TimeNs t = 0; t <= 3000 * kMs; t += 100 * kMs) base.push(t, 0.8, 0.0);
  auto r = base.reader();
  // The command acts from step 20 (20 ms): step 20 + i drives (i + 1) * 0.5 mm/s.
  for (int k = 0; k < 20; ++k) ASSERT_EQ(at(*r, k * kMs).speed, 0.0) << k;
  for (int i = 0; i < 1599; ++i) {
    const TruthState s = at(*r, (20 + i) * kMs + kMs / 2);
    ASSERT_NEAR(s.speed, (i + 1) * 0.5 * kStep, 1e-12) << i;
    ASSERT_NEAR(s.accel_body[0], 0.5, 1e-9) << i;
  }
  const TruthState cruising = at(*r, 1700 * kMs);  // 0.8 reached at step 1619
  EXPECT_EQ(cruising.speed, 0.8);
  EXPECT_EQ(cruising.accel_body[0], 0.0);
}

// The watchdog: a command acts for command_timeout_s (0.5 s) after it took
// effect; then the wheels' target is zero and they brake at
// max_wheel_accel. Asserted: full speed up to the timeout, the first
// slower step right after it, -max_wheel_accel while braking, speed exactly
// 0.0 (not a residue) from one step after v / a, and the pose frozen then.
TEST(CommandedBase, WatchdogStopsTheBaseAfterTheTimeout) {
  Base base(commanded_scenario());
  ASSERT_TRUE(base.push(0, 0.5, 0.0));  // in effect at 20 ms, at 0.5 m/s by 519 ms
  auto r = base.reader();
  // 20 ms + 500 ms: the step at 520 ms is still within the timeout.
  EXPECT_EQ(at(*r, 520 * kMs + kMs / 2).speed, 0.5);
  EXPECT_EQ(r->watchdog_stops(), 0);
  EXPECT_NEAR(at(*r, 521 * kMs).speed, 0.499, 1e-12);
  EXPECT_EQ(r->watchdog_stops(), 1);
  for (int i = 0; i < 498; ++i) {
    const TruthState s = at(*r, (522 + i) * kMs);
    ASSERT_NEAR(s.accel_body[0], -1.0, 1e-9) << i;
  }
  EXPECT_GT(at(*r, 1019 * kMs).speed, 0.0);  // 0.5 m/s over 1 m/s^2: 500 steps
  const TruthState stopped = at(*r, 1022 * kMs);
  EXPECT_EQ(stopped.speed, 0.0);
  EXPECT_EQ(stopped.yaw_rate, 0.0);
  for (TimeNs t = 1022 * kMs; t < 2900 * kMs; t += 10 * kMs) {
    const TruthState s = at(*r, t);
    ASSERT_EQ(s.speed, 0.0);
    ASSERT_EQ(s.x, stopped.x);
    ASSERT_EQ(s.wheel_distance[0], stopped.wheel_distance[0]);
  }
  EXPECT_EQ(r->watchdog_stops(), 1);
  // A new command drives again, and its own timeout stops it again.
  ASSERT_TRUE(base.push(2900 * kMs, 0.3, 0.0));
  EXPECT_NEAR(at(*r, 2920 * kMs).speed, 0.001, 1e-15);
  EXPECT_EQ(at(*r, 3400 * kMs).speed, 0.3);
  at(*r, 5000 * kMs);
  EXPECT_EQ(r->watchdog_stops(), 2);
  EXPECT_EQ(at(*r, 5000 * kMs).speed, 0.0);
  EXPECT_EQ(r->late_commands(), 0);
}

TEST(CommandedBase, NothingMovesBeforeIssuedPlusLatency) {
  for (const double latency : {0.02, 0.05}) {
    DriveScenario sc = commanded_scenario();
    sc.base.command_latency_s = latency;
    Base base(sc);
    const TimeNs issued = 100 * kMs + 500'000;  // between steps
    ASSERT_TRUE(base.push(issued, 0.5, 0.3));
    auto r = base.reader();
    // In effect from the first step at or after issued + latency.
    const TimeNs effect = issued + sec_to_ns(latency);
    const TimeNs first = (effect + kMs - 1) / kMs * kMs;
    for (TimeNs t = 0; t < first; t += 100'000) {
      const TruthState s = at(*r, t);
      ASSERT_EQ(s.speed, 0.0) << t;
      ASSERT_EQ(s.x, 0.0) << t;
      ASSERT_EQ(s.heading, 0.0) << t;
      ASSERT_EQ(s.wheel_distance[1], 0.0) << t;
    }
    EXPECT_GT(at(*r, first).speed, 0.0);
    // Before the start the robot rests at the origin.
    const TruthState before = r->truth_at(-1.0);
    EXPECT_EQ(before.t, -1.0);
    EXPECT_EQ(before.x, 0.0);
    EXPECT_EQ(before.speed, 0.0);
  }
}

// A lockstep run: at each 10 ms tick T the devices read truth up to T, then
// the runtime issues a command at T. Readers asking at their own times (an
// IMU's 5 ms, a camera's 33.3 ms, the loop's ticks) get the same states,
// and so does a reader that asks only after the whole run.
TEST(CommandedBase, ReadersFedTheSameCommandsAgreeBitForBit) {
  DriveScenario sc = commanded_scenario();
  sc.slip.noise_fraction = 0.02;
  sc.slip.correlation_time_s = 0.5;
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{2.0, 1.5, 0x02, 0.2};
  Base base(sc);
  auto imu = base.reader();
  auto camera = base.reader();
  auto loop = base.reader();
  std::vector<std::pair<TimeNs, TruthState>> imu_seen, camera_seen, loop_seen;
  TimeNs next_imu = 0, next_camera = 0;
  for (TimeNs tick = 0; tick <= 8000 * kMs; tick += 10 * kMs) {
    for (; next_imu <= tick; next_imu += 5 * kMs) imu_seen.push_back({next_imu, at(*imu, next_imu)});
    for (; next_camera <= tick; next_camera += 33'333'333) {
      camera_seen.push_back({next_camera, at(*camera, next_camera)});
    }
    loop_seen.push_back({tick, at(*loop, tick)});
    // Forward and back, turning both ways, now and then past the wheels' limit.
    const double s = ns_to_sec(tick);
    ASSERT_TRUE(base.push(tick, 1.3 * std::sin(0.7 * s), 1.5 * std::cos(1.1 * s)));
  }
  for (const auto* r : {imu.get(), camera.get(), loop.get()}) {
    EXPECT_EQ(r->late_commands(), 0);
    EXPECT_EQ(r->history_misses(), 0);
    EXPECT_EQ(r->feed_overruns(), 0);
  }
  // The IMU and the loop both asked at every tick.
  std::size_t compared = 0;
  for (const auto& [t, s] : loop_seen) {
    const auto& [ti, si] = imu_seen[static_cast<std::size_t>(t / (5 * kMs))];
    ASSERT_EQ(ti, t);
    ASSERT_TRUE(identical(s, si));
    ++compared;
  }
  EXPECT_EQ(compared, 801u);
  // Afterwards, one reader at everyone's times.
  for (const auto* seen : {&camera_seen, &imu_seen}) {
    auto r = base.reader();
    for (const auto& [t, s] : *seen) ASSERT_TRUE(identical(at(*r, t), s)) << ns_to_sec(t);
  }
  // It moved, both ways, and slipped.
  const TruthState end = loop_seen.back().second;
  EXPECT_GT(std::abs(end.x) + std::abs(end.y), 0.5);
  EXPECT_NE(end.wheel_slip[0], 0.0);
}

TEST(CommandedBase, ALateCommandIsCounted) {
  Base base(commanded_scenario());
  ASSERT_TRUE(base.push(0, 0.2, 0.0));
  auto ahead = base.reader();
  at(*ahead, 1000 * kMs);  // integrated to 1 s
  // Issued at 0.95 s: in effect at 0.97 s, which `ahead` has passed.
  ASSERT_TRUE(base.push(950 * kMs, 0.6, 0.0));
  const TruthState a = at(*ahead, 1100 * kMs);
  EXPECT_EQ(ahead->late_commands(), 1);
  auto behind = base.reader();
  const TruthState b = at(*behind, 1100 * kMs);
  EXPECT_EQ(behind->late_commands(), 0);
  // The late reader applied it 31 steps later: it is 31 mm/s behind.
  EXPECT_NEAR(b.speed - a.speed, 0.031, 1e-12);
}

TEST(CommandedBase, NonFiniteCommandsAreCountedAndStop) {
  Base base(commanded_scenario());
  ASSERT_TRUE(base.push(0, 0.5, 0.2));
  ASSERT_TRUE(base.push(100 * kMs, 0.5, 0.2));
  ASSERT_TRUE(base.push(200 * kMs, std::nan(""), 0.2));
  ASSERT_TRUE(base.push(300 * kMs, 0.5, std::numeric_limits<double>::infinity()));
  EXPECT_EQ(base.feed.non_finite(), 2);
  // Stored as stops: the base brakes from 0.22 s on and never sees a NaN;
  // the watchdog then has nothing to stop.
  auto r = base.reader();
  for (TimeNs t = 0; t <= 2000 * kMs; t += kMs) {
    const TruthState s = at(*r, t);
    for (double v : {s.x, s.y, s.heading, s.speed, s.yaw_rate, s.accel_body[0], s.wheel_distance[0]}) {
      ASSERT_TRUE(std::isfinite(v)) << t;
    }
  }
  EXPECT_EQ(at(*r, 2000 * kMs).speed, 0.0);
  EXPECT_EQ(r->watchdog_stops(), 0);  // stopped by the commands, not by the watchdog
  BaseCommand c;
  ASSERT_TRUE(base.feed.read(2, &c));
  EXPECT_EQ(c.linear, 0.0);
  EXPECT_EQ(c.angular, 0.0);
  // Sent out of order: refused and counted.
  EXPECT_FALSE(base.push(250 * kMs, 0.1, 0.0));
  EXPECT_EQ(base.feed.rejected_out_of_order(), 1);
  EXPECT_EQ(base.feed.published(), 4u);
}

// Without slip the wheels roll exactly their side's ground distance: the
// integral of v -/+ w track / 2, so right - left = heading * track.
TEST(CommandedBase, WheelDistancesAreTheIntegralsOfTheWheelSpeeds) {
  Base base(commanded_scenario());
  for (TimeNs t = 0; t <= 6000 * kMs; t += 50 * kMs) {
    const double s = ns_to_sec(t);
    base.push(t, 0.8 * std::sin(0.9 * s), 1.2 * std::cos(0.5 * s));
  }
  auto r = base.reader();
  double left = 0.0, right = 0.0;
  for (TimeNs t = 0; t < 6000 * kMs; t += kMs) {
    const TruthState s = at(*r, t);
    ASSERT_NEAR(s.wheel_distance[0], left, 1e-9) << t;
    ASSERT_NEAR(s.wheel_distance[1], right, 1e-9) << t;
    ASSERT_NEAR(s.wheel_distance[1] - s.wheel_distance[0], s.heading * 0.5, 1e-9) << t;
    left += (s.speed - 0.25 * s.yaw_rate) * kStep;
    right += (s.speed + 0.25 * s.yaw_rate) * kStep;
  }
  EXPECT_GT(std::abs(left) + std::abs(right), 0.5);
}

TEST(CommandedBase, SlipAddsToTheWheelsOnly) {
  DriveScenario sc = commanded_scenario();
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{2.0, 2.0, 0x01, 0.1};  // the left wheel, 2 s to 4 s
  Base base(sc);
  for (TimeNs t = 0; t <= 6000 * kMs; t += 100 * kMs) base.push(t, 0.5, 0.0);
  auto r = base.reader();
  EXPECT_EQ(at(*r, 1900 * kMs).wheel_slip[0], 0.0);
  const TruthState during = at(*r, 3000 * kMs);
  EXPECT_EQ(during.wheel_slip[0], 0.1);
  EXPECT_EQ(during.wheel_slip[1], 0.0);
  const TruthState after = at(*r, 5000 * kMs);
  EXPECT_EQ(after.wheel_slip[0], 0.0);
  // 10 % of 2 s at 0.5 m/s on the left; the body still drives straight.
  EXPECT_NEAR(after.wheel_distance[0] - after.wheel_distance[1], 0.1, 1e-9);
  EXPECT_EQ(after.heading, 0.0);
  EXPECT_EQ(after.y, 0.0);

  // Continuous slip: each wheel's surplus is the integral of its ground
  // speed times its fraction (trapezoid over the 1 ms steps).
  DriveScenario noisy = commanded_scenario();
  noisy.slip.noise_fraction = 0.05;
  noisy.slip.correlation_time_s = 0.3;
  Base n(noisy);
  for (TimeNs t = 0; t <= 4000 * kMs; t += 100 * kMs) n.push(t, 0.6, 0.4);
  auto q = n.reader();
  double surplus[2] = {0.0, 0.0};
  for (TimeNs t = 0; t < 4000 * kMs; t += kMs) {
    const TruthState s = at(*q, t);
    const double a = ns_to_sec(t), b = ns_to_sec(t + kMs);
    const double side[2] = {s.speed - 0.25 * s.yaw_rate, s.speed + 0.25 * s.yaw_rate};
    for (int w = 0; w < 2; ++w) {
      ASSERT_EQ(s.wheel_slip[w], n.slip.noise_fraction(w, a));
      surplus[w] += side[w] * 0.5 * (n.slip.noise_fraction(w, a) + n.slip.noise_fraction(w, b)) * kStep;
    }
  }
  const TruthState end = at(*q, 4000 * kMs);
  // The ground distances: right - left = heading * track, mean = signed distance.
  const double mean_ground = end.distance;  // forward only here
  const double half_turn = 0.25 * end.heading;
  EXPECT_NEAR(end.wheel_distance[0], mean_ground - half_turn + surplus[0], 1e-9);
  EXPECT_NEAR(end.wheel_distance[1], mean_ground + half_turn + surplus[1], 1e-9);
  EXPECT_GT(std::abs(surplus[0]) + std::abs(surplus[1]), 1e-4);
}

TEST(CommandedBase, SkidSteerIsDifferentialWithTheEffectiveTrack) {
  DriveScenario skid = commanded_scenario();
  skid.robot.kinematics = DriveKinematics::kSkidSteer;
  skid.robot.track_width_m = 0.7;
  skid.robot.wheel_count = 4;
  skid.robot.wheels[0] = SimWheel{1, true, 0.0};
  skid.robot.wheels[1] = SimWheel{3, true, 0.0};
  skid.robot.wheels[2] = SimWheel{2, false, 0.0};
  skid.robot.wheels[3] = SimWheel{4, false, 0.0};
  DriveScenario diff = commanded_scenario();
  diff.robot.track_width_m = 0.7;
  Base a(skid), b(diff);
  for (TimeNs t = 0; t <= 3000 * kMs; t += 100 * kMs) {
    a.push(t, 0.4, 0.9);
    b.push(t, 0.4, 0.9);
  }
  auto ra = a.reader();
  auto rb = b.reader();
  const TruthState sa = at(*ra, 3000 * kMs), sb = at(*rb, 3000 * kMs);
  EXPECT_EQ(sa.wheel_count, 4);
  EXPECT_EQ(sa.x, sb.x);
  EXPECT_EQ(sa.heading, sb.heading);
  EXPECT_EQ(sa.wheel_distance[0], sb.wheel_distance[0]);  // left front
  EXPECT_EQ(sa.wheel_distance[1], sb.wheel_distance[0]);  // left rear
  EXPECT_EQ(sa.wheel_distance[2], sb.wheel_distance[1]);
  EXPECT_EQ(sa.wheel_distance[3], sb.wheel_distance[1]);
}

TEST(CommandedBase, EarlierQueriesAnswerFromTheHistory) {
  Base base(commanded_scenario());
  for (TimeNs t = 0; t <= 2000 * kMs; t += 100 * kMs) base.push(t, 0.5, 0.5);
  auto r = base.reader();
  auto fresh = base.reader();
  at(*r, 1000 * kMs);
  // 255 steps back are kept.
  EXPECT_TRUE(identical(at(*r, 900 * kMs + 300), at(*fresh, 900 * kMs + 300)));
  EXPECT_TRUE(identical(at(*r, 745 * kMs), at(*fresh, 745 * kMs)));
  EXPECT_EQ(r->history_misses(), 0);
  const TruthState old = at(*r, 500 * kMs);  // before the history: its oldest step
  EXPECT_EQ(r->history_misses(), 1);
  EXPECT_EQ(old.t, 0.745);
  EXPECT_TRUE(identical(old, at(*fresh, 745 * kMs)));
  EXPECT_EQ(r->last_step(), 1000);
}

TEST(CommandedBase, AQueryFarAheadIsBoundedAndCounted) {
  Base base(commanded_scenario());
  auto r = base.reader();
  const TruthState s = r->truth_at(700.0);
  EXPECT_EQ(r->far_queries(), 1);
  EXPECT_EQ(s.t, ns_to_sec(600 * kNsPerSec));
  EXPECT_EQ(r->last_step(), CommandedTruth::kMaxStepsPerQuery);
  EXPECT_EQ(r->truth_at(700.0).t, 700.0);
  EXPECT_EQ(r->far_queries(), 1);
  // Out of range and NaN do not integrate at all.
  auto q = base.reader();
  EXPECT_EQ(q->truth_at(std::nan("")).x, 0.0);
  EXPECT_EQ(q->last_step(), -1);
}

TEST(CommandedBase, AReaderLappedByTheFeedCountsWhatItLost) {
  Base base(commanded_scenario());
  const auto extra = std::uint64_t{100};
  for (std::uint64_t i = 0; i < CommandFeed::kCapacity + extra; ++i) {
    ASSERT_TRUE(base.push(static_cast<TimeNs>(i) * kMs, 0.1, 0.0));
  }
  BaseCommand c;
  EXPECT_FALSE(base.feed.read(extra - 1, &c));  // overwritten
  ASSERT_TRUE(base.feed.read(extra, &c));
  EXPECT_EQ(c.issued, kT0 + static_cast<TimeNs>(extra) * kMs);
  EXPECT_FALSE(base.feed.read(CommandFeed::kCapacity + extra, &c));  // not yet
  auto r = base.reader();
  at(*r, 1000 * kMs);
  EXPECT_EQ(r->feed_overruns(), static_cast<std::int64_t>(extra));
}

TEST(CommandedBase, TruthAtDoesNotAllocate) {
  DriveScenario sc = commanded_scenario();
  sc.slip.noise_fraction = 0.01;
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{1.0, 1.0, 0x01, 0.2};
  Base base(sc);
  auto r = base.reader();
  double sink = 0.0;
  {
    rtfuse::test::AllocScope scope;
    for (TimeNs t = 0; t <= 5000 * kMs; t += 3 * kMs) {
      if (t % (30 * kMs) == 0) base.push(t, 0.7, -0.4);
      const TruthState s = at(*r, t);
      sink += s.x + s.wheel_distance[0] + at(*r, t > 100 * kMs ? t - 100 * kMs : 0).y;
    }
    sink += r->truth_at(400.0).x;  // a long catch-up
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_TRUE(std::isfinite(sink));
}

// The whole robot in lockstep: commands pushed at each tick, before the
// devices run up to it, reach every device's reader before they act.
TEST(CommandedBase, ALockstepDriveOfTheCommandedRobotIsDeterministic) {
  const ConfigLoadResult loaded = load_config_string(test::sim_toml_text(false), test::kSimTomlPath);
  ASSERT_TRUE(loaded.ok());
  std::string text;
  {
    std::ifstream in(RTFUSE_SOURCE_DIR "/config/scenarios/obstacle_goals.toml");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  const std::size_t at_duration = text.find("duration_s = 240.0");
  ASSERT_NE(at_duration, std::string::npos);
  text.replace(at_duration, 18, "duration_s = 6.0");
  test::TempFile scenario("commanded_drive", ".toml");
  std::ofstream(scenario.path()) << text;

  DriveOptions opt;
  opt.scenario_path = scenario.path();
  std::int64_t compared = 0;
  SimRobot* seen = nullptr;  // valid during the drive only
  SimRobot::CommandedCounters counters;
  std::int64_t encoder_late = -1;
  opt.before_tick = [&](TimeNs t, SimRobot& robot) {
    seen = &robot;
    ASSERT_TRUE(robot.commanded());
    EXPECT_EQ(robot.goals().size(), 10u);
    const double s = ns_to_sec(t - robot.start_time());
    robot.commands().push(BaseCommand{t, s < 4.0 ? 0.4 : 0.0, s < 2.0 ? 0.3 : -0.3});
  };
  opt.after_tick = [&](TimeNs t, const Snapshot&, const TruthState& truth) {
    // The IMU's newest sample, through the IMU's own reader, against the
    // robot's truth at the same instant.
    SimImu* imu = seen->device<SimImu>("imu");
    ASSERT_NE(imu, nullptr);
    std::int64_t k = (t - seen->start_time()) / 5'000'000;
    while (imu->sample_time(k) > t) --k;
    const TruthState then = seen->truth_at(imu->sample_time(k));
    EXPECT_EQ(imu->ideal_sample(k).gyro_rad_s[2], then.yaw_rate);
    EXPECT_EQ(truth.t, ns_to_sec(t - seen->start_time()));
    ++compared;
    counters = seen->commanded_counters();
    ASSERT_NE(seen->device_truth("wheel_encoders"), nullptr);
    encoder_late = seen->device_truth("wheel_encoders")->late_commands();
  };
  const DriveResult r = run_sim_drive(*loaded.config, opt, nullptr);
  ASSERT_TRUE(r.ok) << r.error;
  std::printf("commanded drive: %lld ticks, %.1f s; raw wheels x %.3f y %.3f; fused final error %.4f m\n",
              static_cast<long long>(r.ticks), r.duration_s, r.final.wheel_odometry.x, r.final.wheel_odometry.y,
              r.final_error_m);
  EXPECT_GT(compared, 1000);
  EXPECT_EQ(counters.late_commands, 0);
  EXPECT_EQ(counters.feed_overruns, 0);
  EXPECT_EQ(counters.history_misses, 0);
  EXPECT_EQ(counters.rejected_commands, 0);
  EXPECT_EQ(encoder_late, 0);
  // It drove: the wheels saw it, and the estimate followed.
  EXPECT_TRUE(r.final.wheel_odometry.valid);
  EXPECT_GT(std::abs(r.final.wheel_odometry.x), 0.5);
  EXPECT_LT(r.final_error_m, 0.2);
}

}  // namespace commanded_base_test
}  // namespace rtfuse::sim
