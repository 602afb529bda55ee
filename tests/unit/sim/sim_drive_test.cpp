// run_sim_drive on config/sim.toml: the real drivers, FusionCore and
// Publisher on the bus-level simulated robot, in lockstep. A drive ends
// where its scenario says, close to the ground truth, says why when the
// config does not match the robot, and is the same every time.
#include "sim/sim_drive.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "runtime/config/config_loader.hpp"
#include "support/sim_toml.hpp"

namespace rtfuse::sim {
namespace sim_drive_test {

const std::string kSimToml = RTFUSE_SOURCE_DIR "/config/sim.toml";
const std::string kStraight = RTFUSE_SOURCE_DIR "/config/scenarios/straight.toml";

RuntimeConfig load_sim_toml() {
  const ConfigLoadResult r = load_config_string(test::sim_toml_text(false), kSimToml);
  for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
  return r.ok() ? *r.config : RuntimeConfig{};
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// straight.toml with some text replaced, written where the test can leave it.
std::string variant_of_straight(const std::string& name,
                                std::initializer_list<std::pair<const char*, const char*>> edits) {
  std::string text = read_text(kStraight);
  for (const auto& [from, to] : edits) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << "straight.toml has no '" << from << "'";
    if (at != std::string::npos) text.replace(at, std::strlen(from), to);
  }
  const std::string path = testing::TempDir() + "rtfuse_drive_" + name + "_" + std::to_string(::getpid()) + ".toml";
  std::ofstream(path) << text;
  return path;
}

TEST(SimulatedDrive, StraightRunEndsCloseToTheTruth) {
  const RuntimeConfig cfg = load_sim_toml();
  DriveOptions opt;
  opt.scenario_path = kStraight;
  const DriveResult r = run_sim_drive(cfg, opt, nullptr);
  ASSERT_TRUE(r.ok) << r.error;
  std::printf("straight: %lld ticks, %.1f s; fused final %.4f m rms %.4f m yaw %.5f rad; "
              "raw wheels final %.4f m rms %.4f m; raw x %.3f y %.3f\n",
              static_cast<long long>(r.ticks), r.duration_s, r.final_error_m, r.rms_error_m, r.final_yaw_error_rad,
              r.raw_final_error_m, r.raw_rms_error_m, r.final.wheel_odometry.x, r.final.wheel_odometry.y);
  EXPECT_DOUBLE_EQ(r.duration_s, 20.0);
  EXPECT_EQ(r.ticks, 20 * 200 + 1);  // t0 .. t0 + 20 s inclusive
  EXPECT_EQ(r.recording_lost, 0);
  EXPECT_TRUE(r.final.initialized);
  for (double v : r.final.state) ASSERT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(r.final_error_m) && std::isfinite(r.rms_error_m));
  EXPECT_LT(r.final_error_m, 1.0);
  EXPECT_LT(r.rms_error_m, 0.5);
  EXPECT_LT(r.final_yaw_error_rad, 0.1);
  // The robot drove 10 m along x and stopped.
  EXPECT_NEAR(r.final.state[0], 10.0, 1.0);
  EXPECT_NEAR(r.final.state[6], 0.0, 0.05) << "vx at rest";
  // Raw wheel odometry is there and dead-reckons the same run.
  ASSERT_TRUE(r.final.wheel_odometry.valid);
  EXPECT_GT(r.raw_final_error_m, 0.0);
  EXPECT_LT(r.raw_final_error_m, 1.0);
  EXPECT_GT(r.raw_rms_error_m, 0.0);
  EXPECT_NEAR(r.final.wheel_odometry.x, 10.0, 1.0);
  // The encoders and the IMU ran the whole drive: one SYNC per tick.
  ASSERT_EQ(r.final.num_devices, 5);
  EXPECT_STREQ(r.final.devices[0].name.c_str(), "can bus");
  EXPECT_EQ(r.final.devices[0].level, DeviceLevel::kOk);
  EXPECT_EQ(r.final.devices[0].values[1], r.ticks) << r.final.devices[0].keys[1];
  EXPECT_STREQ(r.final.devices[4].name.c_str(), "imu");
  EXPECT_EQ(r.final.devices[4].level, DeviceLevel::kOk);
  EXPECT_GE(r.final.devices[4].values[0], 20 * 200 - 2) << "IMU samples at 200 Hz";
}

TEST(SimulatedDrive, NodeIdTheRobotDoesNotHaveIsNamed) {
  const RuntimeConfig cfg = load_sim_toml();
  DriveOptions opt;
  opt.scenario_path = variant_of_straight("node5", {{"left_nodes = [1]", "left_nodes = [5]"}});
  const DriveResult r = run_sim_drive(cfg, opt, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.ticks, 0);
  EXPECT_EQ(r.error, kSimToml + ": can.node[0].node_id = 1 is not an encoder of the simulated robot in " +
                         opt.scenario_path);
  std::remove(opt.scenario_path.c_str());
}

TEST(SimulatedDrive, EncoderWidthOrDirectionTheRobotDoesNotHaveIsNamed) {
  const RuntimeConfig cfg = load_sim_toml();  // 32-bit unsigned, counting up
  DriveOptions opt;
  opt.scenario_path = variant_of_straight("bits16", {{"encoder_bits = 32", "encoder_bits = 16"}});
  DriveResult r = run_sim_drive(cfg, opt, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, kSimToml + ": can.node[0] reads a 32-bit unsigned position but the simulated encoder in " +
                         opt.scenario_path + " counts 16-bit unsigned");
  std::remove(opt.scenario_path.c_str());
  opt.scenario_path = variant_of_straight("inverted", {{"[robot]", "[robot]\ninvert_right = true"}});
  r = run_sim_drive(cfg, opt, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, kSimToml + ": can.node[1].sign = 1 but the simulated encoder in " + opt.scenario_path +
                         " counts down driving forward");
  std::remove(opt.scenario_path.c_str());
}

TEST(SimulatedDrive, SameDriveTwiceIsBitIdentical) {
  const RuntimeConfig cfg = load_sim_toml();
  DriveOptions opt;
  // 2 m instead of 10: 2 s stop, 4 s driving, 2 s stop, 1 s more.
  opt.scenario_path =
      variant_of_straight("short", {{"duration_s = 20.0", "duration_s = 9.0"}, {"length_m = 10.0", "length_m = 2.0"}});
  const DriveResult a = run_sim_drive(cfg, opt, nullptr);
  const DriveResult b = run_sim_drive(cfg, opt, nullptr);
  std::remove(opt.scenario_path.c_str());
  ASSERT_TRUE(a.ok) << a.error;
  ASSERT_TRUE(b.ok) << b.error;
  EXPECT_EQ(a.ticks, 9 * 200 + 1);
  EXPECT_EQ(a.ticks, b.ticks);
  EXPECT_GT(std::abs(a.final.state[0]), 0.5) << "the robot moved";
  EXPECT_EQ(std::memcmp(a.final.state, b.final.state, sizeof a.final.state), 0);
  EXPECT_EQ(std::memcmp(a.final.covariance, b.final.covariance, sizeof a.final.covariance), 0);
  EXPECT_EQ(a.final.seq, b.final.seq);
  EXPECT_EQ(a.final.stamp_ns, b.final.stamp_ns);
  EXPECT_EQ(std::memcmp(&a.final.wheel_odometry.x, &b.final.wheel_odometry.x, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&a.rms_error_m, &b.rms_error_m, sizeof(double)), 0);
  for (int i = 0; i < a.final.num_sensors; ++i) EXPECT_EQ(a.final.sensors[i].accepted, b.final.sensors[i].accepted);
}

}  // namespace sim_drive_test
}  // namespace rtfuse::sim
