// The navigator on the loop's side and its own thread, with a stand-in for
// the mapper's grid and a unicycle for the robot: goals planned and
// followed to within the tolerance, each stop reason a zero command on
// the command tick it appears at, bad goals refused with their reason, a
// path the map blocks re-planned or stopped at, the commands independent
// of when the navigator's thread runs, and nothing allocated per tick.
#include "runtime/devices/navigator/navigator_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "navigation/stop_reason.hpp"
#include "rtfuse/nav_stop_t.hpp"
#include "rtfuse/pose_stamped_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "support/alloc_counter.hpp"
#include "support/sim_toml.hpp"

namespace rtfuse {
namespace navigator_device_test {

using navigation::StopReason;
constexpr TimeNs kTick = 10'000'000;  // a 100 Hz loop
constexpr int kSide = 120;            // 6 m at 0.05 m, the odom origin in the middle

class FakeGrid final : public GridSource {
 public:
  bool attach(GridConsumer& c, std::string*) override {
    consumer = &c;
    return true;
  }
  GridLayout grid_layout() const noexcept override { return GridLayout{kSide, kSide, 0.05, -3.0, -3.0}; }
  GridConsumer* consumer = nullptr;
};

std::vector<std::int8_t> free_grid() { return std::vector<std::int8_t>(kSide * kSide, 0); }

// A wall of occupied cells across x = wall_x from y_from to y_to (metres).
void wall(std::vector<std::int8_t>& g, double wall_x, double y_from, double y_to) {
  const int cx = static_cast<int>(std::floor((wall_x + 3.0) / 0.05));
  for (int y = 0; y < kSide; ++y) {
    const double cy = -3.0 + (y + 0.5) * 0.05;
    if (cy >= y_from && cy <= y_to) g[static_cast<std::size_t>(y * kSide + cx)] = 100;
  }
}

std::vector<std::uint8_t> goal_bytes(double x, double y, const char* frame = "odom") {
  rtfuse::pose_stamped_t m{};
  m.header.frame_id = frame;
  m.pose.position.x = x;
  m.pose.position.y = y;
  m.pose.orientation.w = 1.0;
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::vector<std::uint8_t> stop_bytes(bool stop) {
  rtfuse::nav_stop_t m{};
  m.header.frame_id = "base_link";
  m.stop = stop;
  m.reason = "test";
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

struct Command {
  TimeNs t;
  double linear, angular;
  StopReason reason;
  bool operator==(const Command& o) const {
    return t == o.t && linear == o.linear && angular == o.angular && reason == o.reason;
  }
};

// The loop's side as the tick pipeline drives it, the navigator's thread
// stepped every `worker_every` ticks (1: lockstep), a unicycle that moves
// as commanded, and grids delivered as the mapper would.
struct Rig {
  explicit Rig(const std::string& extra = "follow = true\n") {
    const std::string text = test::sim_toml_text(true, true) + "\n[navigation]\n" + extra;
    ConfigLoadResult r = load_config_string(text, test::kSimTomlPath);
    for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
    std::string err;
    core = FusionCore::create(*r.config, &err);
    EXPECT_TRUE(core) << err;
    nav = NavigatorDevice::create(grid, *core, -1, &err);
    EXPECT_TRUE(nav) << err;
    grid.attach(*nav, &err);
  }
  void give_grid(const std::vector<std::int8_t>& cells, TimeNs stamp) {
    grid.consumer->on_grid(cells.data(), stamp);
    grid.consumer->on_map_current(stamp);
  }
  void goal(double x, double y, const char* frame = "odom") {
    const auto b = goal_bytes(x, y, frame);
    nav->on_input(NavigatorDevice::kGoalInput, b.data(), static_cast<int>(b.size()), t);
  }
  void stop(bool on) {
    const auto b = stop_bytes(on);
    nav->on_input(NavigatorDevice::kStopInput, b.data(), static_cast<int>(b.size()), t);
  }
  // One tick: the loop's snapshot, then (every worker_every ticks) the
  // navigator's thread, then the robot moves for a tick.
  void tick() {
    t += kTick;
    ++ticks;
    s.tick_time_ns = t;
    if (!freeze_estimate) s.stamp_ns = t;
    s.initialized = true;
    s.state[0] = x;
    s.state[1] = y;
    s.state[5] = yaw;
    // The mapper takes a keyframe in twice a second while the camera runs.
    if (mapping && ticks % 50 == 0) grid.consumer->on_map_current(t);
    nav->fill_snapshot(s);
    if (ticks % worker_every == 0) nav->step(0);
    if (s.nav.command_due) {
      commands.push_back(Command{t, s.nav.linear_mps, s.nav.angular_rps, reason()});
      v = s.nav.linear_mps;
      w = s.nav.angular_rps;
    }
    const double dt = 1e-9 * static_cast<double>(kTick);
    x += v * std::cos(yaw) * dt;
    y += v * std::sin(yaw) * dt;
    yaw += w * dt;
  }
  void run(double seconds) {
    for (int i = 0; i < static_cast<int>(std::lround(seconds * 100)); ++i) tick();
  }
  StopReason reason() const { return static_cast<StopReason>(s.nav.stop_reason); }

  FakeGrid grid;
  std::unique_ptr<FusionCore> core;
  std::unique_ptr<NavigatorDevice> nav;
  Snapshot s;
  TimeNs t = 1'000'000'000;
  std::int64_t ticks = 0;
  int worker_every = 1;
  bool freeze_estimate = false;
  bool mapping = true;
  double x = 0.0, y = 0.0, yaw = 0.0, v = 0.0, w = 0.0;
  std::vector<Command> commands;
};

TEST(NavigatorDevice, DrivesToAGoalAndStopsThere) {
  Rig r;
  r.give_grid(free_grid(), r.t);
  r.goal(2.0, 1.0);
  r.run(0.05);
  EXPECT_EQ(r.reason(), StopReason::kStaleMap) << "no map is planned on before map_delay has passed";
  r.run(15.0);
  EXPECT_EQ(r.s.nav.goal_state, GoalState::kReached);
  EXPECT_EQ(r.reason(), StopReason::kGoalReached);
  EXPECT_LT(std::hypot(r.x - 2.0, r.y - 1.0), 0.15 + 1e-9);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  EXPECT_EQ(r.s.nav.goal_seq, 1);
  EXPECT_GE(r.s.nav.plan_seq, 1);
  // Commands at 20 Hz on tick time.
  for (std::size_t i = 1; i < r.commands.size(); ++i) ASSERT_EQ(r.commands[i].t - r.commands[i - 1].t, 50'000'000);
  double top = 0.0;
  for (const Command& c : r.commands) top = std::max(top, c.linear);
  EXPECT_GT(top, 0.3) << "it drove at speed somewhere";
  EXPECT_LE(top, 0.5);
}

TEST(NavigatorDevice, EachStopReasonIsAZeroCommandOnItsFirstCommandTick) {
  Rig r;
  r.give_grid(free_grid(), r.t);
  r.goal(2.5, 0.0);
  r.run(2.0);
  ASSERT_EQ(r.reason(), StopReason::kNone);
  ASSERT_GT(r.s.nav.linear_mps, 0.0);
  // A stop: zero on the next command tick, held until released.
  r.stop(true);
  do r.tick(); while (!r.s.nav.command_due);
  EXPECT_EQ(r.reason(), StopReason::kStopCommand);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  EXPECT_EQ(r.s.nav.angular_rps, 0.0);
  r.run(1.0);
  EXPECT_EQ(r.reason(), StopReason::kStopCommand);
  r.stop(false);
  r.run(0.1);
  EXPECT_EQ(r.reason(), StopReason::kNone);
  // A stale estimate: the filter's stamp stops moving.
  r.freeze_estimate = true;
  const TimeNs frozen = r.t;
  while (r.t - frozen <= 500'000'000) r.tick();
  do r.tick(); while (!r.s.nav.command_due);
  EXPECT_EQ(r.reason(), StopReason::kStaleEstimate);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  r.freeze_estimate = false;
  r.run(0.1);
  EXPECT_EQ(r.reason(), StopReason::kNone);
  // A stale map: the mapper stops taking keyframes in (the camera died);
  // map_timeout is 5 s from the last keyframe's capture.
  r.mapping = false;
  r.run(4.4);
  EXPECT_EQ(r.reason(), StopReason::kNone);
  r.run(1.2);
  EXPECT_EQ(r.reason(), StopReason::kStaleMap);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
}

TEST(NavigatorDevice, FollowerOffSendsZeroWithItsReason) {
  Rig r("follow = false\n");
  r.give_grid(free_grid(), r.t);
  r.goal(1.0, 0.0);
  r.run(2.0);
  EXPECT_EQ(r.reason(), StopReason::kDisabled);
  EXPECT_TRUE(r.s.nav.send_command) << "a goal under a disabled follower still gets its zero";
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  EXPECT_GE(r.s.nav.plan_seq, 1) << "the path is still planned and published";
  EXPECT_EQ(r.x, 0.0);
}

TEST(NavigatorDevice, BadGoalsAreRejectedWithTheirReason) {
  Rig r;
  r.give_grid(free_grid(), r.t);
  r.goal(std::numeric_limits<double>::quiet_NaN(), 0.0);
  r.run(0.1);
  EXPECT_EQ(r.s.nav.goal_state, GoalState::kRejected);
  EXPECT_NE(std::string(r.s.nav.goal_error), "");
  r.goal(1.0, 0.0, "map");
  r.run(0.1);
  EXPECT_EQ(r.s.nav.goal_state, GoalState::kRejected);
  EXPECT_NE(std::string(r.s.nav.goal_error).find("frame"), std::string::npos) << r.s.nav.goal_error;
  r.goal(40.0, 0.0);  // the grid is 6 m across
  r.run(1.5);
  EXPECT_EQ(r.s.nav.goal_state, GoalState::kRejected);
  EXPECT_STREQ(r.s.nav.goal_error, "goal outside the grid");
  std::vector<std::int8_t> g = free_grid();
  wall(g, 1.0, -0.5, 0.5);
  r.give_grid(g, r.t);
  r.run(1.2);
  r.goal(1.0, 0.0);  // on the wall
  r.run(1.5);
  EXPECT_EQ(r.s.nav.goal_state, GoalState::kRejected);
  EXPECT_STREQ(r.s.nav.goal_error, "goal in an obstacle");
  EXPECT_EQ(r.s.nav.goal_seq, 4);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  EXPECT_EQ(r.x, 0.0) << "it never moved";
}

TEST(NavigatorDevice, AWallOnThePathIsPlannedAroundOrStoppedAt) {
  Rig r;
  r.give_grid(free_grid(), r.t);
  r.goal(2.5, 0.0);
  r.run(2.0);
  ASSERT_EQ(r.reason(), StopReason::kNone);
  const std::int32_t plans_before = r.s.nav.plan_seq;
  // A wall with a way round: re-planned, and it keeps driving.
  std::vector<std::int8_t> g = free_grid();
  wall(g, 1.8, -1.0, 1.0);
  r.give_grid(g, r.t);
  r.run(1.5);
  EXPECT_GT(r.s.nav.plan_seq, plans_before);
  EXPECT_GE(r.s.nav.replans_blocked, 1);
  EXPECT_EQ(r.reason(), StopReason::kNone);
  // Now across the whole grid: no way round, it stops.
  wall(g, 1.8, -3.0, 3.0);
  r.give_grid(g, r.t);
  r.run(1.5);
  EXPECT_EQ(r.reason(), StopReason::kPathBlocked);
  EXPECT_EQ(r.s.nav.linear_mps, 0.0);
  EXPECT_LT(r.x, 1.8 - 0.3) << "it stopped short of the wall";
}

TEST(NavigatorDevice, CommandsDoNotDependOnWhenItsThreadRuns) {
  std::vector<Command> runs[3];
  const int every[3] = {1, 7, 40};
  for (int k = 0; k < 3; ++k) {
    Rig r;
    r.worker_every = every[k];
    r.give_grid(free_grid(), r.t);
    r.goal(2.0, -1.0);
    r.run(3.0);
    std::vector<std::int8_t> g = free_grid();
    wall(g, 1.2, -2.0, 0.0);
    r.give_grid(g, r.t);
    r.run(8.0);
    runs[k] = r.commands;
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  EXPECT_TRUE(runs[0] == runs[1]);
  EXPECT_TRUE(runs[0] == runs[2]);
}

std::string config_errors(const std::string& navigation, bool with_mapping = true) {
  const ConfigLoadResult r =
      load_config_string(test::sim_toml_text(true, with_mapping) + "\n[navigation]\n" + navigation, test::kSimTomlPath);
  std::string out;
  for (const auto& e : r.errors) out += e.to_string() + "\n";
  return out;
}

TEST(NavigatorConfig, MistakesNameTheKeyAndTheFix) {
  EXPECT_EQ(config_errors("follow = true\nmax_linear = 0.3\nunknown = \"blocked\"\n"), "");
  std::string e = config_errors("max_linaer = 0.3\n");
  EXPECT_NE(e.find("max_linaer"), std::string::npos) << e;
  e = config_errors("max_linear = -1\n");
  EXPECT_NE(e.find("navigation.max_linear"), std::string::npos) << e;
  EXPECT_NE(e.find("must be in (0, 100] m/s"), std::string::npos) << e;
  e = config_errors("unknown = \"maybe\"\n");
  EXPECT_NE(e.find("\"free\""), std::string::npos) << e;
  e = config_errors("min_lookahead = 2.0\nmax_lookahead = 1.0\n");
  EXPECT_NE(e.find("lookahead"), std::string::npos) << e;
  e = config_errors("follow = true\n", false);
  EXPECT_NE(e.find("needs a [mapping] section"), std::string::npos) << e;
}

TEST(NavigatorDevice, NothingAllocatesPerTick) {
  Rig r;
  const std::vector<std::int8_t> g = free_grid();
  const auto goal = goal_bytes(2.0, 0.5);
  const auto stop = stop_bytes(false);
  r.give_grid(g, r.t);
  r.run(0.5);
  test::AllocScope count;
  r.nav->on_input(NavigatorDevice::kGoalInput, goal.data(), static_cast<int>(goal.size()), r.t);
  r.nav->on_input(NavigatorDevice::kStopInput, stop.data(), static_cast<int>(stop.size()), r.t);
  for (int i = 0; i < 300; ++i) {
    r.s.tick_time_ns = r.t += kTick;
    r.s.stamp_ns = r.t;
    r.s.initialized = true;
    r.nav->fill_snapshot(r.s);
    r.nav->step(0);
    if (i % 100 == 0) {
      r.grid.consumer->on_grid(g.data(), r.t);
      r.grid.consumer->on_map_current(r.t);
    }
  }
  EXPECT_EQ(count.count(), 0u);
  EXPECT_GE(r.s.nav.plan_seq, 1);
}

}  // namespace navigator_device_test
}  // namespace rtfuse
