// The loop closed in lockstep: config/sim_nav.toml's robot starts with an
// empty map, is sent to a goal behind a wall its camera has not seen yet,
// plans straight through the unknown, finds the wall in its own map,
// re-plans round it and arrives, its true centre never closer to the wall
// than its footprint's radius at any tick; the drive's recording replays
// byte for byte, the goal and every velocity command included.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "sim/sim_drive.hpp"
#include "support/device_values.hpp"
#include "transport/event_log.hpp"

namespace nav_drive_test {
using namespace rtfuse;  // NOLINT

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// obstacle_goals.toml's robot, base and IMU with one wall 3 m ahead, 2.4 m
// wide, and one goal 3 m behind it: the straight line runs into the wall's
// middle, and the way round is 1.2 m to either side. The first goal goes
// out after 3 s of standstill and is reached after some 27 s.
std::string wall_scenario() {
  std::string text = read_file(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/obstacle_goals.toml");
  const std::size_t goals = text.find("\n[[goal]]");
  const std::size_t robot = text.find("\n[robot]");
  EXPECT_NE(goals, std::string::npos);
  EXPECT_NE(robot, std::string::npos);
  text = text.substr(0, goals) +
         "\n[[goal]]\nx_m = 6.0\ny_m = 0.0\n"
         "\n[[obstacle]]\nx_m = 3.0\ny_m = 0.0\nsize_x_m = 0.4\nsize_y_m = 2.4\nheight_m = 1.0\n" +
         text.substr(robot);
  const std::string from = "duration_s = 240.0";
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, from.size(), "duration_s = 31.0");
  const std::string path = testing::TempDir() + "rtfuse_nav_wall_" + std::to_string(::getpid()) + ".toml";
  std::ofstream(path) << text;
  return path;
}

TEST(NavDrive, FindsTheWallInItsOwnMapGoesRoundAndItsRecordingReplays) {
  // The camera at 15 fps: half the rendering (the test's cost), the same
  // keyframes for the map.
  std::string text = read_file(std::string(RTFUSE_SOURCE_DIR) + "/config/sim_nav.toml");
  const std::string fps = "\nfps = 30\n";
  const std::size_t at_fps = text.find(fps);
  ASSERT_NE(at_fps, std::string::npos);
  text.replace(at_fps, fps.size(), "\nfps = 15\n");
  const ConfigLoadResult r = load_config_string(text, std::string(RTFUSE_SOURCE_DIR) + "/config/sim_nav.toml");
  ASSERT_TRUE(r.config) << test::config_errors(r);
  const std::string path = testing::TempDir() + "rtfuse_nav_drive_" + std::to_string(::getpid()) + ".lcm";
  sim::DriveOptions options;
  options.scenario_path = wall_scenario();
  options.record_path = path;
  options.config_text = text;
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
  std::remove(options.scenario_path.c_str());
  ASSERT_TRUE(d.ok) << d.error;
  ASSERT_EQ(d.goals.size(), 1u);
  EXPECT_TRUE(d.goals[0].reached) << d.goals[0].why << ", stop reason " << int(d.final.nav.stop_reason)
                                  << ", " << d.final.nav.remaining_m << " m to go at " << d.duration_s << " s";
  EXPECT_LT(d.goals[0].truth_error_m, 0.3);
  // The robot is 0.5 m across.
  EXPECT_GE(d.min_obstacle_distance_m, 0.25);
  EXPECT_GE(d.final.nav.replans_blocked, 1) << "the wall was found after the first plan";
  EXPECT_EQ(d.late_commands, 0) << "every simulated device saw the same base";
  EXPECT_GT(d.commands, 0);
  EXPECT_EQ(d.recording_lost, 0);

  transport::EventLogReader reader;
  std::string err;
  ASSERT_TRUE(reader.open(path, &err)) << err;
  HalRecording rec;
  ASSERT_TRUE(load_hal_recording(reader, {}, &rec, &err)) << err;
  EXPECT_EQ(rec.inputs.size(), 1u) << "the goal is in the recording";
  const HalReplayResult replay = replay_hal_recording(rec, *r.config, nullptr, nullptr);
  std::remove(path.c_str());
  ASSERT_TRUE(replay.ok) << replay.error;
  EXPECT_EQ(replay.identical, replay.compared) << replay.first_mismatch;
  EXPECT_EQ(replay.recorded_not_reproduced, 0);
  EXPECT_EQ(replay.final.nav.goal_state, GoalState::kReached);
  EXPECT_EQ(replay.final.nav.plan_seq, d.final.nav.plan_seq);
}

// The closed loop: the whole obstacle course as config/sim_nav.toml
// drives it, ten goals in turn from an empty map, each reached within 0.3 m
// of the truth, never nearer an obstacle than the footprint's radius. The
// scenario's 240 s are cut to 180: its last goal is reached after some
// 160 s. That the closed
// loop's recording replays is the test above's (this drive's is 7 GB).
TEST(NavDrive, TheObstacleCoursesTenGoalsEachReachedWithin30CmOfTheTruth) {
  std::string scenario = read_file(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/obstacle_goals.toml");
  const std::string from = "duration_s = 240.0";
  const std::size_t at = scenario.find(from);
  ASSERT_NE(at, std::string::npos);
  scenario.replace(at, from.size(), "duration_s = 180.0");
  sim::DriveOptions options;
  options.scenario_path = testing::TempDir() + "rtfuse_nav_course_" + std::to_string(::getpid()) + ".toml";
  std::ofstream(options.scenario_path) << scenario;
  const std::string config_path = std::string(RTFUSE_SOURCE_DIR) + "/config/sim_nav.toml";
  options.config_text = read_file(config_path);
  const ConfigLoadResult r = load_config_string(options.config_text, config_path);
  ASSERT_TRUE(r.config) << test::config_errors(r);
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
  std::remove(options.scenario_path.c_str());
  ASSERT_TRUE(d.ok) << d.error;
  ASSERT_EQ(d.goals.size(), 10u);
  for (std::size_t i = 0; i < d.goals.size(); ++i) {
    EXPECT_TRUE(d.goals[i].reached) << "goal " << i + 1 << ": " << d.goals[i].why;
    EXPECT_LT(d.goals[i].truth_error_m, 0.3) << "goal " << i + 1;
  }
  EXPECT_GE(d.min_obstacle_distance_m, 0.25);
  // No plan failed and no goal was refused: with a voxel occupied at two
  // hits (sim_nav.toml) no stray match lies on a path or a goal (at one
  // hit, 3 of 13 plans were re-plans and a 15 fps drive had a goal refused
  // as "goal in an obstacle"). A path the map shows blocked is re-planned
  // in the test above, on the same course.
  EXPECT_EQ(d.final.nav.plan_failures, 0);
  EXPECT_EQ(d.late_commands, 0);
  EXPECT_EQ(d.history_misses, 0);
}

}  // namespace nav_drive_test
