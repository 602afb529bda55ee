// The command gate: each stop an exact zero on the very step its condition
// appears, the documented priority over every combination of conditions,
// the acceleration limits and dt's fallbacks, acceleration from zero after
// a stop, never backwards, the counts and names; then the follower, the
// clearance check and the gate on thousands of steps of garbage (NaN,
// infinities, huge numbers, random paths and stamps), every output finite
// and within the limits; no allocation.
#include "navigation/command_gate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "navigation/path_clearance.hpp"
#include "navigation/path_follower.hpp"
#include "support/alloc_counter.hpp"

namespace command_gate_test {

using namespace rtfuse::navigation;
using rtfuse::TimeNs;

constexpr TimeNs kPeriod = 50'000'000;  // 20 Hz
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Everything in order at now: the gate drives.
GateInput all_well(TimeNs now) {
  GateInput in;
  in.now = now;
  in.enabled = in.have_goal = in.have_path = in.estimate_finite = true;
  in.estimate_stamp = in.map_stamp = now;
  return in;
}

// A gate stepped up to a cruise (0.3 m/s, 0.5 rad/s) by time now.
struct Cruising {
  CommandGate gate{FollowerParams{}};
  TimeNs now = 10 * rtfuse::kNsPerSec;
  Cruising() {
    for (int k = 0; k < 40; ++k, now += kPeriod) gate.step(all_well(now), Velocity2{0.3, 0.5});
  }
};

TEST(CommandGate, ItDrivesWhenAllIsWell) {
  Cruising c;
  EXPECT_EQ(c.gate.last_reason(), StopReason::kNone);
  EXPECT_DOUBLE_EQ(c.gate.last_command().linear, 0.3);
  EXPECT_DOUBLE_EQ(c.gate.last_command().angular, 0.5);
  EXPECT_EQ(c.gate.count(StopReason::kNone), 40u);
  EXPECT_EQ(c.gate.period_ns(), kPeriod);
}

TEST(CommandGate, EachStopIsAnExactZeroOnTheStepItAppears) {
  const FollowerParams p;
  struct Case {
    StopReason reason;
    void (*make)(GateInput&);
  };
  const Case cases[] = {
      {StopReason::kDisabled, [](GateInput& in) { in.enabled = false; }},
      {StopReason::kStopCommand, [](GateInput& in) { in.stop_requested = true; }},
      {StopReason::kBadPose, [](GateInput& in) { in.estimate_finite = false; }},
      {StopReason::kNoGoal, [](GateInput& in) { in.have_goal = false; }},
      {StopReason::kGoalReached, [](GateInput& in) { in.goal_reached = true; }},
      {StopReason::kNoPath, [](GateInput& in) { in.have_path = false; }},
      {StopReason::kPathBlocked, [](GateInput& in) { in.path_blocked = true; }},
      {StopReason::kStaleMap, [](GateInput& in) { in.map_stamp = 0; }},
  };
  for (const Case& k : cases) {
    Cruising c;
    GateInput in = all_well(c.now);
    k.make(in);
    const GateOutput out = c.gate.step(in, Velocity2{0.3, 0.5});
    EXPECT_EQ(out.reason, k.reason) << to_string(k.reason);
    EXPECT_TRUE(out.stopped());
    EXPECT_EQ(out.command.linear, 0.0) << to_string(k.reason);  // exactly: not ramped down
    EXPECT_EQ(out.command.angular, 0.0) << to_string(k.reason);
    EXPECT_EQ(c.gate.last_reason(), k.reason);
    EXPECT_EQ(c.gate.count(k.reason), 1u);
  }
  // A command that is not finite.
  for (const Velocity2 bad : {Velocity2{kNan, 0.0}, Velocity2{0.1, -kInf}, Velocity2{kInf, 0.2}}) {
    Cruising c;
    const GateOutput out = c.gate.step(all_well(c.now), bad);
    EXPECT_EQ(out.reason, StopReason::kBadCommand);
    EXPECT_EQ(out.command.linear, 0.0);
    EXPECT_EQ(out.command.angular, 0.0);
  }
  // The estimate goes stale as time passes: at the timeout it is still
  // fresh, one nanosecond later it is not.
  {
    Cruising c;
    const TimeNs stamp = c.now;
    const TimeNs timeout = rtfuse::sec_to_ns(p.estimate_timeout_s);
    GateInput in = all_well(stamp + timeout);
    in.estimate_stamp = stamp;
    EXPECT_EQ(c.gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kNone);
    in.now = stamp + timeout + 1;
    in.map_stamp = in.now;
    const GateOutput out = c.gate.step(in, Velocity2{0.3, 0.5});
    EXPECT_EQ(out.reason, StopReason::kStaleEstimate);
    EXPECT_EQ(out.command.linear, 0.0);
    EXPECT_EQ(out.command.angular, 0.0);
    // As far in the future is as stale.
    in.estimate_stamp = in.now + timeout + 1;
    EXPECT_EQ(c.gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kStaleEstimate);
    in.estimate_stamp = in.now + timeout;
    EXPECT_EQ(c.gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kNone);
  }
  {
    Cruising c;
    const TimeNs stamp = c.now;
    const TimeNs timeout = rtfuse::sec_to_ns(p.map_timeout_s);
    GateInput in = all_well(stamp + timeout);
    in.map_stamp = stamp;
    EXPECT_EQ(c.gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kNone);
    in.now = stamp + timeout + 1;
    in.estimate_stamp = in.now;
    const GateOutput out = c.gate.step(in, Velocity2{0.3, 0.5});
    EXPECT_EQ(out.reason, StopReason::kStaleMap);
    EXPECT_EQ(out.command.linear, 0.0);
    EXPECT_EQ(out.command.angular, 0.0);
  }
  // Stamps whose difference overflows are stale, not undefined.
  {
    CommandGate gate{p};
    GateInput in = all_well(std::numeric_limits<TimeNs>::max());
    in.estimate_stamp = std::numeric_limits<TimeNs>::min();
    EXPECT_EQ(gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kStaleEstimate);
    in.estimate_stamp = in.now;
    in.map_stamp = std::numeric_limits<TimeNs>::min();
    EXPECT_EQ(gate.step(in, Velocity2{0.3, 0.5}).reason, StopReason::kStaleMap);
  }
}

TEST(CommandGate, StopsTakeTheDocumentedPriority) {
  // The conditions in the documented order; for every combination the
  // reason is the first that holds.
  const StopReason order[] = {StopReason::kDisabled,  StopReason::kStopCommand, StopReason::kBadPose,
                              StopReason::kStaleEstimate, StopReason::kStaleMap, StopReason::kNoGoal,
                              StopReason::kGoalReached, StopReason::kNoPath,   StopReason::kPathBlocked,
                              StopReason::kBadCommand};
  constexpr int kConditions = 10;
  CommandGate gate{FollowerParams{}};
  const TimeNs now = 100 * rtfuse::kNsPerSec;
  std::set<StopReason> seen;
  for (int mask = 0; mask < (1 << kConditions); ++mask) {
    GateInput in = all_well(now);
    Velocity2 desired{0.2, 0.1};
    const auto on = [mask](int i) { return (mask >> i & 1) != 0; };
    if (on(0)) in.enabled = false;
    if (on(1)) in.stop_requested = true;
    if (on(2)) in.estimate_finite = false;
    if (on(3)) in.estimate_stamp = now - 2 * rtfuse::kNsPerSec;
    if (on(4)) in.map_stamp = (mask & 0x100) ? 0 : now - 60 * rtfuse::kNsPerSec;
    if (on(5)) in.have_goal = false;
    if (on(6)) in.goal_reached = true;
    if (on(7)) in.have_path = false;
    if (on(8)) in.path_blocked = true;
    if (on(9)) desired.linear = kNan;
    StopReason expected = StopReason::kNone;
    for (int i = 0; i < kConditions; ++i) {
      if (on(i)) {
        expected = order[i];
        break;
      }
    }
    EXPECT_EQ(gate.decide(in, desired), expected) << "conditions " << mask;
    const GateOutput out = gate.step(in, desired);
    ASSERT_EQ(out.reason, expected) << "conditions " << mask;
    if (expected != StopReason::kNone) {
      EXPECT_EQ(out.command.linear, 0.0);
      EXPECT_EQ(out.command.angular, 0.0);
    }
    seen.insert(out.reason);
  }
  EXPECT_EQ(seen.size(), 11u);
  EXPECT_EQ(gate.steps(), 1024u);
  // Each reason's count: the combinations whose first condition it is
  // (2^(10 - 1 - i) of them), kNone once.
  for (int i = 0; i < kConditions; ++i) EXPECT_EQ(gate.count(order[i]), 1u << (kConditions - 1 - i)) << i;
  EXPECT_EQ(gate.count(StopReason::kNone), 1u);
  EXPECT_EQ(gate.count(static_cast<StopReason>(200)), 0u);
}

TEST(CommandGate, AccelerationIsLimitedAndRestartsFromZeroAfterAStop) {
  const FollowerParams p;  // 0.5 m/s^2 up, 1.0 down, 2.0 rad/s^2: 0.025, 0.05, 0.1 a period
  CommandGate gate{p};
  TimeNs now = rtfuse::kNsPerSec;
  GateOutput out = gate.step(all_well(now), Velocity2{0.5, 1.0});
  EXPECT_DOUBLE_EQ(out.dt_s, 0.05);  // the first step: one period
  EXPECT_DOUBLE_EQ(out.command.linear, 0.025);
  EXPECT_DOUBLE_EQ(out.command.angular, 0.1);
  for (int k = 2; k <= 30; ++k) {
    now += kPeriod;
    out = gate.step(all_well(now), Velocity2{0.5, 1.0});
    EXPECT_NEAR(out.command.linear, std::min(0.5, 0.025 * k), 1e-12) << k;
    EXPECT_NEAR(out.command.angular, std::min(1.0, 0.1 * k), 1e-12) << k;
  }
  EXPECT_EQ(out.command.linear, 0.5);
  EXPECT_EQ(out.command.angular, 1.0);
  // Slowing: 0.05 m/s and 0.1 rad/s a period.
  now += kPeriod;
  out = gate.step(all_well(now), Velocity2{0.0, -1.0});
  EXPECT_NEAR(out.command.linear, 0.45, 1e-12);
  EXPECT_NEAR(out.command.angular, 0.9, 1e-12);
  // A stop: zero at once; then from zero again.
  now += kPeriod;
  GateInput in = all_well(now);
  in.path_blocked = true;
  out = gate.step(in, Velocity2{0.5, 1.0});
  EXPECT_EQ(out.command.linear, 0.0);
  EXPECT_EQ(out.command.angular, 0.0);
  EXPECT_EQ(out.dt_s, 0.0);
  now += kPeriod;
  out = gate.step(all_well(now), Velocity2{0.5, -1.0});
  EXPECT_DOUBLE_EQ(out.command.linear, 0.025);
  EXPECT_DOUBLE_EQ(out.command.angular, -0.1);
  // A restart forgets the last step: the next is a first step.
  gate.restart();
  EXPECT_EQ(gate.last_command().linear, 0.0);
  out = gate.step(all_well(now + 7 * kPeriod), Velocity2{0.5, 0.0});
  EXPECT_DOUBLE_EQ(out.dt_s, 0.05);
  EXPECT_DOUBLE_EQ(out.command.linear, 0.025);
}

TEST(CommandGate, DtIsTheTimeSinceTheLastStepWithinTwoPeriods) {
  CommandGate gate{FollowerParams{}};
  TimeNs now = 5 * rtfuse::kNsPerSec;
  gate.step(all_well(now), Velocity2{0.5, 0.0});  // 0.025
  struct Step {
    TimeNs advance;
    double dt;
  };
  const Step steps[] = {
      {30'000'000, 0.03},   // early: 0.015 more
      {100'000'000, 0.1},   // two periods: still its own
      {100'000'001, 0.05},  // later than that: one period
      {0, 0.05},            // no time passed
      {-20'000'000, 0.05},  // backwards
      {3'600 * rtfuse::kNsPerSec, 0.05},
  };
  double v = 0.025;
  for (const Step& s : steps) {
    now += s.advance;
    const GateOutput out = gate.step(all_well(now), Velocity2{0.5, 0.0});
    EXPECT_NEAR(out.dt_s, s.dt, 1e-15) << s.advance;
    v += 0.5 * s.dt;
    EXPECT_NEAR(out.command.linear, v, 1e-12) << s.advance;
  }
}

TEST(CommandGate, ItNeverReversesAndClampsToTheLimits) {
  const FollowerParams p;
  CommandGate gate{p};
  TimeNs now = rtfuse::kNsPerSec;
  for (int k = 0; k < 100; ++k, now += kPeriod) {
    const GateOutput out = gate.step(all_well(now), Velocity2{-0.4, k < 50 ? 1e300 : -1e300});
    EXPECT_EQ(out.reason, StopReason::kNone);
    EXPECT_EQ(out.command.linear, 0.0);
    EXPECT_LE(std::fabs(out.command.angular), p.max_angular_rps);
  }
  EXPECT_EQ(gate.last_command().angular, -p.max_angular_rps);
  for (int k = 0; k < 40; ++k, now += kPeriod) gate.step(all_well(now), Velocity2{1e300, 0.0});
  EXPECT_EQ(gate.last_command().linear, p.max_linear_mps);
  FollowerParams bad;
  bad.command_rate_hz = kNan;
  EXPECT_THROW(CommandGate{bad}, std::invalid_argument);
}

TEST(CommandGate, ReasonsHaveTheirDiagnosticNames) {
  const std::pair<StopReason, const char*> names[] = {
      {StopReason::kNone, "none"},
      {StopReason::kDisabled, "disabled"},
      {StopReason::kNoGoal, "no_goal"},
      {StopReason::kGoalReached, "goal_reached"},
      {StopReason::kStaleEstimate, "stale_estimate"},
      {StopReason::kStaleMap, "stale_map"},
      {StopReason::kPathBlocked, "path_blocked"},
      {StopReason::kStopCommand, "stop_command"},
      {StopReason::kNoPath, "no_path"},
      {StopReason::kBadPose, "bad_pose"},
      {StopReason::kBadCommand, "bad_command"},
  };
  std::set<std::string> distinct;
  for (const auto& [reason, name] : names) {
    EXPECT_STREQ(to_string(reason), name);
    distinct.insert(name);
  }
  EXPECT_EQ(distinct.size(), static_cast<std::size_t>(kStopReasonCount));
  EXPECT_STREQ(to_string(static_cast<StopReason>(99)), "unknown");
}

// Garbage for the property test: mostly sane values, some NaN, infinities,
// huge and tiny numbers.
struct Garbage {
  std::mt19937_64 rng;
  explicit Garbage(std::uint64_t seed) : rng(seed) {}
  double unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }
  bool chance(double p) { return unit() < p; }
  double value(double sane) {
    switch (rng() % 16) {
      case 0: return kNan;
      case 1: return kInf;
      case 2: return -kInf;
      case 3: return (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, static_cast<double>(rng() % 600) - 300.0);
      case 4: {  // any bit pattern
        const std::uint64_t bits = rng();
        double d;
        std::memcpy(&d, &bits, sizeof d);
        return d;
      }
      default: return (unit() * 2.0 - 1.0) * sane;
    }
  }
};

TEST(CommandGate, TheFollowerAndGateOnGarbageStayWithinTheLimits) {
  const FollowerParams p;
  PathFollower follower(p, 64);
  CommandGate gate(p);
  // A 2 m square costmap with a few obstacles, for path_blocked.
  std::vector<std::uint8_t> cost(40 * 40, kCostFree);
  for (int k = 0; k < 12; ++k) cost[static_cast<std::size_t>(k * 131 % 1600)] = kCostLethal;
  const CostView costs{cost.data(), 40, 40};
  const GridGeometry geometry{-1.0, -1.0, 0.05};
  Garbage g(2028);
  std::vector<Point2> path(80);
  TimeNs now = 0, last_now = 0;
  bool first = true;
  Velocity2 last;
  int driving = 0, stops = 0, paths = 0;
  for (int step = 0; step < 6000; ++step) {
    if (step % 50 == 0 || g.chance(0.01)) {
      const int n = static_cast<int>(g.rng() % 80);  // over the capacity sometimes
      const bool sane = g.chance(0.7);
      for (int i = 0; i < n; ++i) path[i] = Point2{sane ? (g.unit() * 2 - 1) : g.value(5.0), sane ? (g.unit() * 2 - 1) : g.value(5.0)};
      paths += follower.set_path(path.data(), n);
    }
    // Time: mostly a period on, sometimes garbage.
    switch (g.rng() % 10) {
      case 0: now = static_cast<TimeNs>(g.rng()); break;
      case 1: now -= static_cast<TimeNs>(g.rng() % 1'000'000'000); break;
      case 2: now += static_cast<TimeNs>(g.rng() % 400'000'000); break;
      default: now += kPeriod;
    }
    const Pose2 pose{g.chance(0.8) ? g.unit() * 2 - 1 : g.value(3.0), g.chance(0.8) ? g.unit() * 2 - 1 : g.value(3.0),
                     g.chance(0.8) ? g.unit() * 7 - 3.5 : g.value(10.0)};
    const double speed = g.chance(0.7) ? last.linear : g.value(1.0);
    const FollowResult r = follower.follow(pose, speed);
    ASSERT_TRUE(std::isfinite(r.command.linear) && std::isfinite(r.command.angular)) << step;
    ASSERT_TRUE(r.command.linear >= 0.0 && r.command.linear <= p.max_linear_mps) << step;
    ASSERT_LE(std::fabs(r.command.angular), p.max_angular_rps) << step;
    ASSERT_TRUE(std::isfinite(r.remaining_m) && std::isfinite(r.cross_track_m) && std::isfinite(r.curvature)) << step;
    GateInput in = all_well(now);
    in.enabled = g.chance(0.97);
    in.stop_requested = g.chance(0.02);
    in.estimate_finite = usable(pose);
    in.estimate_stamp = g.chance(0.9) ? now - static_cast<TimeNs>(g.rng() % 600'000'000) : static_cast<TimeNs>(g.rng());
    in.map_stamp = g.chance(0.95) ? now : static_cast<TimeNs>(g.rng() % 3);
    in.have_goal = g.chance(0.98);
    in.have_path = follower.has_path();
    in.goal_reached = r.reached();
    in.path_blocked = follower.has_path() &&
                      path_blocked(costs, geometry, follower.path(), follower.path_size(), r.nearest_index, r.nearest,
                                   g.chance(0.9) ? p.blocked_check_distance_m : g.value(100.0),
                                   static_cast<std::uint8_t>(p.lethal_from));
    const Velocity2 desired = g.chance(0.8) ? r.command : Velocity2{g.value(2.0), g.value(4.0)};
    const GateOutput out = gate.step(in, desired);
    const Velocity2 c = out.command;
    ASSERT_TRUE(std::isfinite(c.linear) && std::isfinite(c.angular)) << step;
    ASSERT_TRUE(c.linear >= 0.0 && c.linear <= p.max_linear_mps) << step << ": " << c.linear;
    ASSERT_LE(std::fabs(c.angular), p.max_angular_rps) << step;
    if (out.stopped()) {
      ASSERT_EQ(c.linear, 0.0);
      ASSERT_EQ(c.angular, 0.0);
      ++stops;
    } else {
      // dt as the gate documents it, worked out here.
      double dt = 0.05;
      if (!first && now > last_now && static_cast<std::uint64_t>(now) - static_cast<std::uint64_t>(last_now) <=
                                           static_cast<std::uint64_t>(2 * kPeriod)) {
        dt = static_cast<double>(now - last_now) * 1e-9;
      }
      ASSERT_NEAR(out.dt_s, dt, 1e-15) << step;
      ASSERT_LE(c.linear - last.linear, p.max_linear_accel_mps2 * dt + 1e-12) << step;
      ASSERT_LE(last.linear - c.linear, p.max_linear_decel_mps2 * dt + 1e-12) << step;
      ASSERT_LE(std::fabs(c.angular - last.angular), p.max_angular_accel_rps2 * dt + 1e-12) << step;
      ++driving;
    }
    first = false;
    last_now = now;
    last = c;
  }
  // The garbage exercised both ways out.
  EXPECT_GT(driving, 500);
  EXPECT_GT(stops, 500);
  EXPECT_GT(paths, 50);
}

TEST(CommandGate, SteppingAllocatesNothing) {
  CommandGate gate{FollowerParams{}};
  TimeNs now = rtfuse::kNsPerSec;
  double sum = 0.0;
  rtfuse::test::AllocScope scope;
  for (int k = 0; k < 1000; ++k, now += kPeriod) {
    GateInput in = all_well(now);
    in.path_blocked = k % 97 == 0;
    in.estimate_stamp = k % 89 == 0 ? 0 : now;
    sum += gate.step(in, Velocity2{0.4, k % 2 ? 0.5 : kNan}).command.linear;
    sum += std::strlen(to_string(gate.last_reason()));
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(sum, 0.0);
}

}  // namespace command_gate_test
