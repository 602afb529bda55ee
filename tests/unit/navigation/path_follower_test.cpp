// Regulated pure pursuit: closed loops (a unicycle integrated at 20 Hz
// through the follower and the gate) on a straight path, an L and an arc,
// each reaching its goal with a small cross-track error and every command
// within the limits; the lookahead point, the curvature and the speed
// regulation against hand-worked values; turning in place for a path
// behind; progress that never goes back; refused paths, bad poses; the
// parameters' check; no allocation.
#include "navigation/path_follower.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "navigation/command_gate.hpp"
#include "support/alloc_counter.hpp"

namespace path_follower_test {

using namespace rtfuse::navigation;
using rtfuse::TimeNs;

constexpr double kPi = 3.141592653589793;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Points every step metres from a to b, both included.
std::vector<Point2> line(Point2 a, Point2 b, double step, std::vector<Point2> path = {}) {
  const double length = std::sqrt((b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y));
  const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
  for (int i = path.empty() ? 0 : 1; i <= n; ++i) {
    path.push_back(Point2{a.x + (b.x - a.x) * i / n, a.y + (b.y - a.y) * i / n});
  }
  return path;
}

// A unicycle moved along the arc of a constant command for dt.
Pose2 drive(Pose2 p, Velocity2 v, double dt) {
  if (std::fabs(v.angular) < 1e-9) {
    p.x += v.linear * std::cos(p.yaw) * dt;
    p.y += v.linear * std::sin(p.yaw) * dt;
  } else {
    const double yaw = p.yaw + v.angular * dt;
    p.x += v.linear / v.angular * (std::sin(yaw) - std::sin(p.yaw));
    p.y -= v.linear / v.angular * (std::cos(yaw) - std::cos(p.yaw));
    p.yaw = yaw;
  }
  return p;
}

struct Loop {
  bool reached = false;
  int steps = 0;
  Pose2 end;
  double max_cross_track = 0.0;  // after the settle distance
  double max_linear = 0.0;
  double max_angular = 0.0;
  int rotating_steps = 0;
  int limit_violations = 0;
};

// The follower and the gate in a 20 Hz loop around a perfect unicycle.
// Cross-track errors count once the robot has gone settle_m along the path.
Loop run(const std::vector<Point2>& path, Pose2 start, const FollowerParams& p, int max_steps = 2000,
         double settle_m = 0.0) {
  PathFollower follower(p, 4096);
  CommandGate gate(p);
  EXPECT_TRUE(follower.set_path(path.data(), static_cast<int>(path.size())));
  Loop loop;
  Pose2 pose = start;
  Velocity2 last;
  const double total = [&] {
    double s = 0.0;
    for (std::size_t i = 1; i < path.size(); ++i) {
      const double dx = path[i].x - path[i - 1].x, dy = path[i].y - path[i - 1].y;
      s += std::sqrt(dx * dx + dy * dy);
    }
    return s;
  }();
  TimeNs now = 1'000'000'000;
  for (int k = 0; k < max_steps; ++k, now += 50'000'000) {
    const FollowResult r = follower.follow(pose, last.linear);
    GateInput in;
    in.now = now;
    in.enabled = in.have_goal = in.have_path = in.estimate_finite = true;
    in.estimate_stamp = in.map_stamp = now;
    in.goal_reached = r.reached();
    const GateOutput out = gate.step(in, r.command);
    const Velocity2 c = out.command;
    const bool within = std::isfinite(c.linear) && std::isfinite(c.angular) && c.linear >= 0.0 &&
                        c.linear <= p.max_linear_mps && std::fabs(c.angular) <= p.max_angular_rps;
    const bool smooth = out.stopped() ? (c.linear == 0.0 && c.angular == 0.0)
                                      : (c.linear - last.linear <= p.max_linear_accel_mps2 * 0.05 + 1e-12 &&
                                         last.linear - c.linear <= p.max_linear_decel_mps2 * 0.05 + 1e-12 &&
                                         std::fabs(c.angular - last.angular) <= p.max_angular_accel_rps2 * 0.05 + 1e-12);
    loop.limit_violations += !within || !smooth;
    loop.max_linear = std::max(loop.max_linear, c.linear);
    loop.max_angular = std::max(loop.max_angular, std::fabs(c.angular));
    loop.rotating_steps += r.state == FollowState::kRotating;
    if (total - r.remaining_m >= settle_m) loop.max_cross_track = std::max(loop.max_cross_track, r.cross_track_m);
    if (out.reason == StopReason::kGoalReached) {
      EXPECT_EQ(c.linear, 0.0);
      EXPECT_EQ(c.angular, 0.0);
      loop.reached = true;
      break;
    }
    EXPECT_EQ(out.reason, StopReason::kNone) << "step " << k;
    pose = drive(pose, c, 0.05);
    last = c;
    loop.steps = k + 1;
  }
  loop.end = pose;
  return loop;
}

double distance(Pose2 a, Point2 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y)); }

TEST(PathFollower, AStraightPathIsFollowedCloselyToItsEnd) {
  const FollowerParams p;
  const std::vector<Point2> path = line({0.0, 0.0}, {5.0, 0.0}, 0.05);  // a planner's cells: 5 cm apart
  const Loop loop = run(path, Pose2{0.0, 0.1, 0.1}, p, 2000, 2.0);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
  EXPECT_LE(distance(loop.end, path.back()), p.goal_tolerance_m);
  EXPECT_LT(loop.max_cross_track, 0.002);  // 10 cm off at the start, on it within 2 m
  // Heading away at the start, it never gets much farther off.
  EXPECT_LT(run(path, Pose2{0.0, 0.1, 0.1}, p).max_cross_track, 0.105);
  EXPECT_DOUBLE_EQ(loop.max_linear, p.max_linear_mps);  // open ground: full speed
  // 5 m at 0.5 m/s is 200 steps; the ramps and the approach add some.
  EXPECT_GT(loop.steps, 200);
  EXPECT_LT(loop.steps, 320);
  EXPECT_EQ(loop.rotating_steps, 0);
}

TEST(PathFollower, AnLShapedPathIsFollowedRoundItsCorner) {
  const FollowerParams p;
  // As the smoother leaves a planner's path: its corners only.
  const std::vector<Point2> path{{0.0, 0.0}, {3.0, 0.0}, {3.0, 3.0}};
  const Loop loop = run(path, Pose2{0.0, 0.0, 0.0}, p);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
  EXPECT_LE(distance(loop.end, path.back()), p.goal_tolerance_m);
  EXPECT_LT(loop.max_cross_track, 0.15);  // pure pursuit cuts the corner by a fraction of L
  EXPECT_GT(loop.max_cross_track, 0.02);
  // The same path with a planner's 5 cm points: the same run, to rounding.
  std::vector<Point2> dense = line({0.0, 0.0}, {3.0, 0.0}, 0.05);
  dense = line({3.0, 0.0}, {3.0, 3.0}, 0.05, dense);
  const Loop dense_loop = run(dense, Pose2{0.0, 0.0, 0.0}, p);
  EXPECT_TRUE(dense_loop.reached);
  EXPECT_EQ(dense_loop.limit_violations, 0);
  EXPECT_NEAR(dense_loop.max_cross_track, loop.max_cross_track, 1e-6);
}

TEST(PathFollower, AnArcIsFollowedAtTheRegulatedSpeed) {
  const FollowerParams p;
  // A half circle of radius 0.6 m, below regulated_min_radius_m (0.9).
  std::vector<Point2> arc;
  for (int i = 0; i <= 60; ++i) {
    const double a = -kPi / 2 + kPi * i / 60;
    arc.push_back(Point2{0.6 * std::cos(a), 0.6 + 0.6 * std::sin(a)});
  }
  const Loop loop = run(arc, Pose2{0.0, 0.0, 0.0}, p, 2000, 0.3);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
  EXPECT_LE(distance(loop.end, arc.back()), p.goal_tolerance_m);
  EXPECT_LT(loop.max_cross_track, 0.05);
  // Slowed by the radius: well below the maximum all along.
  EXPECT_LT(loop.max_linear, 0.45);
  EXPECT_EQ(loop.rotating_steps, 0);
}

TEST(PathFollower, APathBehindTheRobotIsTakenByTurningInPlace) {
  const FollowerParams p;
  PathFollower f(p, 256);
  const std::vector<Point2> path = line({0.0, 0.0}, {-3.0, 0.0}, 0.05);
  ASSERT_TRUE(f.set_path(path.data(), static_cast<int>(path.size())));
  const FollowResult r = f.follow(Pose2{0.0, 0.0, 0.1}, 0.0);
  EXPECT_EQ(r.state, FollowState::kRotating);
  EXPECT_EQ(r.command.linear, 0.0);
  EXPECT_EQ(r.command.angular, p.max_angular_rps);  // yaw 0.1: the short way is counter-clockwise
  EXPECT_EQ(f.follow(Pose2{0.0, 0.0, -0.1}, 0.0).command.angular, -p.max_angular_rps);
  // Closed loop: it turns, never backs up, and gets there.
  const Loop loop = run(path, Pose2{0.0, 0.0, 0.1}, p);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
  EXPECT_GT(loop.rotating_steps, 40);  // 2.4 rad at most 1 rad/s, from standstill
  EXPECT_LE(distance(loop.end, path.back()), p.goal_tolerance_m);
}

TEST(PathFollower, ItSlowsDownInProportionNearTheGoal) {
  FollowerParams p;
  PathFollower f(p, 256);
  const std::vector<Point2> path = line({0.0, 0.0}, {4.0, 0.0}, 0.5);
  ASSERT_TRUE(f.set_path(path.data(), static_cast<int>(path.size())));
  // On the path, heading along it: the curvature is 0, only the approach.
  EXPECT_DOUBLE_EQ(f.follow(Pose2{1.0, 0.0, 0.0}, 0.5).command.linear, 0.5);
  EXPECT_DOUBLE_EQ(f.follow(Pose2{3.3, 0.0, 0.0}, 0.5).command.linear, 0.5);
  FollowResult r = f.follow(Pose2{3.7, 0.0, 0.0}, 0.5);
  EXPECT_NEAR(r.remaining_m, 0.3, 1e-12);
  EXPECT_NEAR(r.command.linear, 0.5 * 0.3 / 0.6, 1e-12);
  EXPECT_EQ(r.command.angular, 0.0);
  r = f.follow(Pose2{3.83, 0.0, 0.0}, 0.5);
  EXPECT_NEAR(r.command.linear, 0.5 * 0.17 / 0.6, 1e-12);
  // Never below the floor before the goal.
  p.min_approach_speed_mps = 0.2;
  PathFollower g(p, 256);
  ASSERT_TRUE(g.set_path(path.data(), static_cast<int>(path.size())));
  g.follow(Pose2{2.0, 0.0, 0.0}, 0.5);  // the nearest point looked for 2 m at a time
  EXPECT_DOUBLE_EQ(g.follow(Pose2{3.83, 0.0, 0.0}, 0.5).command.linear, 0.2);
  // approach_distance_m 0: no slowing.
  p.approach_distance_m = 0.0;
  PathFollower h(p, 256);
  ASSERT_TRUE(h.set_path(path.data(), static_cast<int>(path.size())));
  h.follow(Pose2{2.0, 0.0, 0.0}, 0.5);
  EXPECT_DOUBLE_EQ(h.follow(Pose2{3.83, 0.0, 0.0}, 0.5).command.linear, 0.5);
  // Within the tolerance: reached, zero.
  r = f.follow(Pose2{3.86, 0.0, 0.0}, 0.5);
  EXPECT_TRUE(r.reached());
  EXPECT_EQ(r.command.linear, 0.0);
  EXPECT_EQ(r.command.angular, 0.0);
}

TEST(PathFollower, TheLookaheadPointAndCurvatureAreRegulatedPurePursuits) {
  FollowerParams p;
  PathFollower f(p, 16);
  // A straight path 0.2 m to the robot's left; L = 0.3 at standstill.
  const std::vector<Point2> path{{-1.0, 0.2}, {10.0, 0.2}};
  ASSERT_TRUE(f.set_path(path.data(), 2));
  FollowResult r = f.follow(Pose2{0.0, 0.0, 0.0}, 0.0);
  EXPECT_DOUBLE_EQ(r.lookahead_m, 0.3);
  EXPECT_NEAR(r.lookahead.x, std::sqrt(0.09 - 0.04), 1e-12);
  EXPECT_NEAR(r.lookahead.y, 0.2, 1e-12);
  EXPECT_NEAR(r.cross_track_m, 0.2, 1e-12);
  EXPECT_NEAR(r.nearest.x, 0.0, 1e-12);
  const double k = 2.0 * 0.2 / 0.09;
  EXPECT_NEAR(r.curvature, k, 1e-9);
  // Radius 0.225 below 0.9: speed 0.5 * 0.225 / 0.9; angular = v k.
  EXPECT_NEAR(r.command.linear, 0.5 * (1.0 / k) / 0.9, 1e-12);
  EXPECT_NEAR(r.command.angular, r.command.linear * k, 1e-12);
  // Without the curvature regulation the angular limit lowers the speed
  // instead, keeping the arc.
  p.regulated_min_radius_m = 0.0;
  PathFollower g(p, 16);
  ASSERT_TRUE(g.set_path(path.data(), 2));
  r = g.follow(Pose2{0.0, 0.0, 0.0}, 0.0);
  EXPECT_DOUBLE_EQ(r.command.angular, p.max_angular_rps);
  EXPECT_NEAR(r.command.linear, p.max_angular_rps / k, 1e-12);
  // The lookahead distance grows with the speed, within its bounds; a speed
  // that is not finite counts as none.
  const std::vector<Point2> straight{{0.0, 0.0}, {10.0, 0.0}};
  ASSERT_TRUE(f.set_path(straight.data(), 2));
  for (const auto& [speed, expected] : std::vector<std::pair<double, double>>{
           {0.0, 0.3}, {0.2, 0.3}, {0.6, 0.6}, {-0.6, 0.6}, {2.0, 0.9}, {1e308, 0.9}, {kNan, 0.3}, {kInf, 0.3}}) {
    r = f.follow(Pose2{1.0, 0.0, 0.0}, speed);
    EXPECT_DOUBLE_EQ(r.lookahead_m, expected) << speed;
    EXPECT_NEAR(r.lookahead.x, 1.0 + expected, 1e-12) << speed;
    EXPECT_DOUBLE_EQ(r.command.linear, 0.5) << speed;
  }
  // Off the path by more than L: it heads for the nearest point.
  r = f.follow(Pose2{2.0, 1.0, kPi / 2 * 3}, 0.0);
  EXPECT_NEAR(r.lookahead.x, 2.0, 1e-12);
  EXPECT_NEAR(r.lookahead.y, 0.0, 1e-12);
  EXPECT_NEAR(r.curvature, 0.0, 1e-12);
}

TEST(PathFollower, ProgressNeverGoesBackAndTheSearchIsBounded) {
  const FollowerParams p;
  PathFollower f(p, 512);
  // Out along y = 0 and back along y = 0.2: a hairpin.
  std::vector<Point2> hairpin = line({0.0, 0.0}, {2.0, 0.0}, 0.1);
  hairpin = line({2.0, 0.0}, {2.0, 0.2}, 0.1, hairpin);
  hairpin = line({2.0, 0.2}, {0.0, 0.2}, 0.1, hairpin);
  ASSERT_TRUE(f.set_path(hairpin.data(), static_cast<int>(hairpin.size())));
  FollowResult r = f.follow(Pose2{1.5, 0.01, 0.0}, 0.0);
  EXPECT_EQ(r.nearest_index, 15);  // on the way out
  r = f.follow(Pose2{1.95, 0.18, kPi}, 0.0);
  EXPECT_GE(r.nearest_index, 21);  // the way back
  const int back = r.nearest_index;
  // Back to the start of the path: the way out is not found again.
  r = f.follow(Pose2{0.5, 0.0, 0.0}, 0.0);
  EXPECT_GE(r.nearest_index, back);
  EXPECT_GE(f.progress(), back);
  // A loop whose end is at its start (20 m round): at the start, not reached.
  std::vector<Point2> loop;
  for (int i = 0; i <= 400; ++i) {
    const double a = 2.0 * kPi * i / 400;
    loop.push_back(Point2{3.183 * std::sin(a), 3.183 - 3.183 * std::cos(a)});
  }
  ASSERT_TRUE(f.set_path(loop.data(), static_cast<int>(loop.size())));
  r = f.follow(Pose2{0.0, 0.0, 0.0}, 0.0);
  EXPECT_FALSE(r.reached());
  EXPECT_EQ(r.nearest_index, 0);
  EXPECT_NEAR(r.remaining_m, 20.0, 0.01);
  // A jump far ahead: the nearest point catches up a window at a time.
  r = f.follow(Pose2{0.0, 6.366, kPi}, 0.0);  // half way round
  EXPECT_LE(r.remaining_m, 20.0);
  EXPECT_GT(r.remaining_m, 10.0 + 0.5);
  for (int k = 0; k < 10; ++k) r = f.follow(Pose2{0.0, 6.366, kPi}, 0.0);
  EXPECT_NEAR(r.remaining_m, 10.0, 0.01);
  EXPECT_EQ(r.nearest_index, 200);
}

TEST(PathFollower, ReachingIsKeptUntilANewPath) {
  const FollowerParams p;
  PathFollower f(p, 64);
  const std::vector<Point2> path = line({0.0, 0.0}, {1.0, 0.0}, 0.1);
  ASSERT_TRUE(f.set_path(path.data(), static_cast<int>(path.size())));
  EXPECT_TRUE(f.follow(Pose2{0.9, 0.0, 0.0}, 0.0).reached());
  const FollowResult drifted = f.follow(Pose2{0.5, 0.3, 0.0}, 0.0);
  EXPECT_TRUE(drifted.reached());
  EXPECT_EQ(drifted.command.linear, 0.0);
  EXPECT_TRUE(f.follow(Pose2{kNan, 0.0, 0.0}, 0.0).reached());  // reached is not about the pose
  ASSERT_TRUE(f.set_path(path.data(), static_cast<int>(path.size())));
  EXPECT_FALSE(f.follow(Pose2{0.5, 0.0, 0.0}, 0.0).reached());
  // A one-point path is reached within the tolerance, pursued outside it.
  const Point2 goal{2.0, 1.0};
  ASSERT_TRUE(f.set_path(&goal, 1));
  FollowResult r = f.follow(Pose2{0.0, 1.0, 0.0}, 0.0);
  EXPECT_EQ(r.state, FollowState::kTracking);
  EXPECT_DOUBLE_EQ(r.command.linear, 0.5);
  EXPECT_EQ(r.remaining_m, 0.0);
  EXPECT_NEAR(r.cross_track_m, 2.0, 1e-12);
  EXPECT_TRUE(f.follow(Pose2{1.9, 1.0, 0.0}, 0.0).reached());
  const Loop loop = run(std::vector<Point2>{goal}, Pose2{0.0, 0.0, 1.0}, p);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
}

TEST(PathFollower, BadPathsAreRefusedAndDropTheOldOne) {
  const FollowerParams p;
  PathFollower f(p, 8);
  const std::vector<Point2> good = line({0.0, 0.0}, {1.0, 0.0}, 0.25);
  const auto refused = [&](const std::vector<Point2>& path, int n) {
    EXPECT_TRUE(f.set_path(good.data(), static_cast<int>(good.size())));
    const bool accepted = f.set_path(path.data(), n);
    EXPECT_FALSE(f.has_path());
    EXPECT_EQ(f.follow(Pose2{}, 0.0).state, FollowState::kNoPath);
    EXPECT_EQ(f.follow(Pose2{}, 0.0).command.linear, 0.0);
    return !accepted;
  };
  EXPECT_TRUE(refused(good, 0));
  EXPECT_TRUE(refused(good, -1));
  EXPECT_TRUE(refused(std::vector<Point2>(9), 9));  // over the capacity
  EXPECT_TRUE(refused(std::vector<Point2>{{0.0, 0.0}, {kNan, 1.0}}, 2));
  EXPECT_TRUE(refused(std::vector<Point2>{{0.0, 0.0}, {1.0, -kInf}}, 2));
  EXPECT_TRUE(refused(std::vector<Point2>{{0.0, 0.0}, {2e6, 0.0}}, 2));
  EXPECT_TRUE(f.set_path(good.data(), 5));
  EXPECT_FALSE(f.set_path(nullptr, 3));
  EXPECT_FALSE(f.has_path());
  // Repeated points are a path: followed to its end.
  const std::vector<Point2> repeated{{0.0, 0.0}, {0.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}, {2.0, 0.0}};
  EXPECT_TRUE(f.set_path(repeated.data(), 7));
  const Loop loop = run(repeated, Pose2{0.0, 0.0, 0.0}, p);
  EXPECT_TRUE(loop.reached);
  EXPECT_EQ(loop.limit_violations, 0);
  EXPECT_THROW(PathFollower(p, 0), std::invalid_argument);
  FollowerParams bad;
  bad.max_lookahead_m = 0.1;
  EXPECT_THROW(PathFollower(bad, 8), std::invalid_argument);
}

TEST(PathFollower, APoseThatIsNotUsableGivesZero) {
  const FollowerParams p;
  PathFollower f(p, 64);
  const std::vector<Point2> path = line({0.0, 0.0}, {3.0, 0.0}, 0.1);
  ASSERT_TRUE(f.set_path(path.data(), static_cast<int>(path.size())));
  EXPECT_EQ(f.follow(Pose2{1.0, 0.0, 0.0}, 0.5).nearest_index, 10);
  for (const Pose2& pose : {Pose2{kNan, 0.0, 0.0}, Pose2{0.0, kInf, 0.0}, Pose2{0.0, 0.0, kNan},
                            Pose2{0.0, 0.0, -kInf}, Pose2{1e300, 0.0, 0.0}, Pose2{0.0, -2e6, 0.0}}) {
    const FollowResult r = f.follow(pose, 0.5);
    EXPECT_EQ(r.state, FollowState::kBadPose);
    EXPECT_EQ(r.command.linear, 0.0);
    EXPECT_EQ(r.command.angular, 0.0);
    EXPECT_EQ(r.nearest_index, 10);  // progress kept
    EXPECT_TRUE(std::isfinite(r.remaining_m));
  }
  // A huge but finite yaw is an angle like any other.
  const FollowResult r = f.follow(Pose2{1.0, 0.0, 1e300}, 0.5);
  EXPECT_NE(r.state, FollowState::kBadPose);
  EXPECT_TRUE(std::isfinite(r.command.linear) && std::isfinite(r.command.angular));
}

TEST(PathFollower, TheParametersCheckNamesTheBadKey) {
  std::string error = "untouched";
  EXPECT_TRUE(FollowerParams{}.check(&error));
  EXPECT_EQ(error, "untouched");
  EXPECT_TRUE(FollowerParams{}.check(nullptr));
  const auto fault = [](auto set) {
    FollowerParams p;
    set(p);
    std::string e;
    EXPECT_FALSE(p.check(&e));
    EXPECT_FALSE(p.check(nullptr));
    return e;
  };
  EXPECT_EQ(fault([](FollowerParams& p) { p.max_linear_mps = 0.0; }), "max_linear_mps must be in (0, 10]");
  EXPECT_EQ(fault([](FollowerParams& p) { p.max_linear_mps = kNan; }), "max_linear_mps must be in (0, 10]");
  const std::pair<void (*)(FollowerParams&), const char*> keys[] = {
      {[](FollowerParams& p) { p.max_angular_rps = -1.0; }, "max_angular_rps"},
      {[](FollowerParams& p) { p.max_linear_accel_mps2 = kInf; }, "max_linear_accel_mps2"},
      {[](FollowerParams& p) { p.max_linear_decel_mps2 = 0.0; }, "max_linear_decel_mps2"},
      {[](FollowerParams& p) { p.max_angular_accel_rps2 = 0.0; }, "max_angular_accel_rps2"},
      {[](FollowerParams& p) { p.lookahead_time_s = -0.1; }, "lookahead_time_s"},
      {[](FollowerParams& p) { p.min_lookahead_m = 0.0; }, "min_lookahead_m"},
      {[](FollowerParams& p) { p.max_lookahead_m = 0.2; }, "max_lookahead_m"},
      {[](FollowerParams& p) { p.search_window_m = 0.0; }, "search_window_m"},
      {[](FollowerParams& p) { p.goal_tolerance_m = 0.0; }, "goal_tolerance_m"},
      {[](FollowerParams& p) { p.approach_distance_m = -1.0; }, "approach_distance_m"},
      {[](FollowerParams& p) { p.min_approach_speed_mps = 0.6; }, "min_approach_speed_mps"},
      {[](FollowerParams& p) { p.min_approach_speed_mps = 0.0; }, "min_approach_speed_mps"},
      {[](FollowerParams& p) { p.regulated_min_radius_m = kNan; }, "regulated_min_radius_m"},
      {[](FollowerParams& p) { p.rotate_to_heading_min_angle_rad = 4.0; }, "rotate_to_heading_min_angle_rad"},
      {[](FollowerParams& p) { p.command_rate_hz = 0.5; }, "command_rate_hz"},
      {[](FollowerParams& p) { p.estimate_timeout_s = 0.0; }, "estimate_timeout_s"},
      {[](FollowerParams& p) { p.map_timeout_s = 1e9; }, "map_timeout_s"},
      {[](FollowerParams& p) { p.blocked_check_distance_m = -0.5; }, "blocked_check_distance_m"},
      {[](FollowerParams& p) { p.lethal_from = 0; }, "lethal_from"},
      {[](FollowerParams& p) { p.lethal_from = 256; }, "lethal_from"},
  };
  for (const auto& [set, key] : keys) {
    const std::string e = fault(set);
    EXPECT_EQ(e.rfind(std::string(key) + " must be", 0), 0u) << e;
  }
}

TEST(PathFollower, SettingAPathAndFollowingAllocateNothing) {
  const FollowerParams p;
  PathFollower f(p, 2048);
  std::vector<Point2> path = line({0.0, 0.0}, {20.0, 0.0}, 0.01);
  path.resize(2001);
  std::vector<Point2> repeated(2048, Point2{1.0, 1.0});
  double sum = 0.0;
  rtfuse::test::AllocScope scope;
  for (int k = 0; k < 3; ++k) {
    f.set_path(path.data(), 2001);
    for (int i = 0; i < 400; ++i) sum += f.follow(Pose2{i * 0.05, 0.1, 0.0}, 0.5).command.linear;
    f.set_path(repeated.data(), 2048);
    sum += f.follow(Pose2{0.0, 0.0, 0.0}, 0.5).command.angular;
    f.set_path(repeated.data(), 4096);  // refused
    sum += f.follow(Pose2{kNan, 0.0, 0.0}, 0.5).command.angular;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(sum, 0.0);
}

}  // namespace path_follower_test
