// Scenario files of the bus-level simulator: what they parse to, and that
// every mistake is reported with its file, line, column and key.
#include "sim/drive_scenario.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/truth_trajectory.hpp"

namespace rtfuse::sim {
namespace drive_scenario_test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// A valid scenario to which each test adds or changes lines.
const std::string kRobot = R"(
[robot]
left_nodes = [1]
right_nodes = [2]
)";

std::string load_error(const std::string& text) {
  DriveScenario sc;
  std::string error;
  EXPECT_FALSE(load_drive_scenario_string(text, "t.toml", &sc, &error)) << text;
  return error;
}

DriveScenario load_ok(const std::string& text) {
  DriveScenario sc;
  std::string error;
  EXPECT_TRUE(load_drive_scenario_string(text, "t.toml", &sc, &error)) << error;
  return sc;
}

TEST(DriveScenario, ShippedScenariosLoadAndCanBeDriven) {
  for (const char* name : {"straight", "turns", "figure_eight", "slip", "dropout", "demo", "gnss_loop", "obstacles"}) {
    const std::string path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/" + name + ".toml";
    DriveScenario sc;
    std::string error;
    ASSERT_TRUE(load_drive_scenario(path, &sc, &error)) << error;
    EXPECT_EQ(sc.source, path);
    EXPECT_FALSE(sc.path.empty()) << name;
    const TruthTrajectory truth(sc);
    EXPECT_TRUE(truth.valid()) << name << ": " << truth.problem().message;
    EXPECT_GT(truth.plan().end_time(), 5.0) << name;
    EXPECT_GE(truth.duration_s(), truth.plan().end_time()) << name;
  }
  DriveScenario demo;
  std::string error;
  ASSERT_TRUE(load_drive_scenario(RTFUSE_SOURCE_DIR "/config/scenarios/demo.toml", &demo, &error)) << error;
  const TruthTrajectory truth(demo);
  // "A few minutes", with the figure eights, a spin, the slip episode and the
  // dropout all inside the drive.
  EXPECT_GT(truth.plan().end_time(), 120.0);
  EXPECT_LE(truth.plan().end_time(), demo.duration_s);
  ASSERT_EQ(demo.dropout_count, 1);
  EXPECT_LT(demo.dropouts[0].start_s + demo.dropouts[0].duration_s, truth.plan().end_time());
  ASSERT_EQ(demo.slip.episode_count, 1);
  EXPECT_LT(demo.slip.episodes[0].start_s + demo.slip.episodes[0].duration_s, truth.plan().end_time());
}

TEST(DriveScenario, EverySegmentTypeParsesToSiUnits) {
  const DriveScenario sc = load_ok(R"(
duration_s = 300.0
seed = 99
[limits]
max_accel_mps2 = 0.8
max_yaw_accel_dps2 = 180.0
[[path]]
type = "straight"
length_m = 3.0
speed_mps = 1.5
[[path]]
type = "straight"
duration_s = 4.0
speed_mps = 0.5
[[path]]
type = "arc"
radius_m = 2.0
angle_deg = -45.0
speed_mps = 1.0
[[path]]
type = "arc"
yaw_rate_dps = 30.0
angle_deg = 90.0
speed_mps = 0.5
[[path]]
type = "spin"
angle_deg = 180.0
yaw_rate_dps = 45.0
[[path]]
type = "figure_eight"
radius_m = 1.5
laps = 2
speed_mps = 0.7
first_turn = "right"
[[path]]
type = "stop"
duration_s = 1.5
)" + kRobot);
  EXPECT_EQ(sc.duration_s, 300.0);
  EXPECT_EQ(sc.seed, 99u);
  EXPECT_DOUBLE_EQ(sc.limits.max_accel_mps2, 0.8);
  EXPECT_DOUBLE_EQ(sc.limits.max_yaw_accel_rad_s2, kPi);
  ASSERT_EQ(sc.path.size(), 7u);
  EXPECT_EQ(sc.path[0].type, SegmentType::kStraight);
  EXPECT_DOUBLE_EQ(sc.path[0].length_m, 3.0);
  EXPECT_DOUBLE_EQ(sc.path[0].speed_mps, 1.5);
  EXPECT_DOUBLE_EQ(sc.path[1].length_m, 2.0);  // duration at cruise speed
  EXPECT_EQ(sc.path[2].type, SegmentType::kArc);
  EXPECT_DOUBLE_EQ(sc.path[2].radius_m, 2.0);
  EXPECT_DOUBLE_EQ(sc.path[2].angle_rad, -45.0 * kDeg);
  EXPECT_DOUBLE_EQ(sc.path[3].radius_m, 0.5 / (30.0 * kDeg));  // speed / yaw rate
  EXPECT_EQ(sc.path[4].type, SegmentType::kSpin);
  EXPECT_DOUBLE_EQ(sc.path[4].yaw_rate_rad_s, 45.0 * kDeg);
  EXPECT_DOUBLE_EQ(sc.path[4].angle_rad, kPi);
  EXPECT_EQ(sc.path[5].type, SegmentType::kFigureEight);
  EXPECT_EQ(sc.path[5].laps, 2);
  EXPECT_TRUE(sc.path[5].right_first);
  EXPECT_EQ(sc.path[6].type, SegmentType::kStop);
  EXPECT_DOUBLE_EQ(sc.path[6].duration_s, 1.5);
  EXPECT_EQ(sc.path[2].line, 16);  // where its `type` is, for later messages
}

TEST(DriveScenario, RobotSlipDropoutsAndImu) {
  const DriveScenario sc = load_ok(R"(
[[path]]
type = "straight"
length_m = 20.0
speed_mps = 1.0
[robot]
kinematics = "skid_steer"
track_width_m = 0.7
wheel_radius_m = 0.15
counts_per_rev = 1024
gear_ratio = 25.0
encoder_bits = 24
encoder_signed = true
heartbeat_period_s = 0.05
left_nodes = [5, 6]
right_nodes = [7, 8]
left_radius_error = [0.01, -0.01]
right_radius_error = [0.0, 0.02]
invert_right = true
[slip]
noise_fraction = 0.02
correlation_time_s = 0.25
[[slip.episode]]
start_s = 3.0
duration_s = 1.0
wheel = "right_rear"
fraction = 0.5
[[slip.episode]]
start_s = 5.0
duration_s = 1.0
wheel = "left"
fraction = -0.2
[[dropout]]
node = 7
start_s = 4.0
duration_s = 2.0
[imu]
model = "mpu9250"
address = 0x69
rate_hz = 500.0
gyro_range_dps = 1000
accel_range_g = 8
gyro_noise_density_dps_rthz = 0.01
accel_noise_density_ug_rthz = 300.0
gyro_bias_dps = [1.0, 2.0, 3.0]
accel_bias_mps2 = [0.1, 0.2, 0.3]
xyz_m = [0.1, 0.2, 0.3]
rpy_deg = [180.0, 0.0, 90.0]
temperature_c = 40.0
vibration_accel_mps2 = 0.4
vibration_gyro_dps = 2.0
vibration_speed_mps = 0.5
)");
  const RobotBody& r = sc.robot;
  EXPECT_EQ(r.kinematics, DriveKinematics::kSkidSteer);
  EXPECT_EQ(r.track_width_m, 0.7);
  EXPECT_EQ(r.counts_per_rev, 1024.0);
  EXPECT_EQ(r.gear_ratio, 25.0);
  EXPECT_EQ(r.encoder_bits, 24);
  EXPECT_TRUE(r.encoder_signed);
  EXPECT_TRUE(r.invert_right);
  EXPECT_FALSE(r.invert_left);
  EXPECT_EQ(r.heartbeat_period_ns, 50'000'000);
  ASSERT_EQ(r.wheel_count, 4);
  // Order: left front, left rear, right front, right rear.
  const std::uint8_t ids[4] = {5, 6, 7, 8};
  const bool left[4] = {true, true, false, false};
  const double errors[4] = {0.01, -0.01, 0.0, 0.02};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r.wheels[i].node_id, ids[i]);
    EXPECT_EQ(r.wheels[i].left, left[i]);
    EXPECT_EQ(r.wheels[i].radius_error, errors[i]);
  }
  EXPECT_EQ(sc.slip.noise_fraction, 0.02);
  EXPECT_EQ(sc.slip.correlation_time_s, 0.25);
  ASSERT_EQ(sc.slip.episode_count, 2);
  EXPECT_EQ(sc.slip.episodes[0].wheel_mask, 0x08);
  EXPECT_EQ(sc.slip.episodes[1].wheel_mask, 0x03);
  EXPECT_EQ(sc.slip.episodes[1].fraction, -0.2);
  ASSERT_EQ(sc.dropout_count, 1);
  EXPECT_EQ(sc.dropouts[0].node_id, 7);
  EXPECT_EQ(sc.dropouts[0].start_s, 4.0);
  EXPECT_EQ(sc.dropouts[0].duration_s, 2.0);
  const SimImuConfig& imu = sc.imu;
  EXPECT_EQ(imu.model, MpuChip::kMpu9250);
  EXPECT_EQ(imu.address, 0x69);
  EXPECT_EQ(imu.rate_hz, 500.0);
  EXPECT_EQ(imu.gyro_range_dps, 1000);
  EXPECT_EQ(imu.accel_range_g, 8);
  EXPECT_DOUBLE_EQ(imu.gyro_noise_density, 0.01 * kDeg);
  EXPECT_DOUBLE_EQ(imu.accel_noise_density, 300e-6 * 9.80665);
  EXPECT_DOUBLE_EQ(imu.gyro_bias_rad_s[2], 3.0 * kDeg);
  EXPECT_EQ(imu.accel_bias_mps2[1], 0.2);
  EXPECT_EQ(imu.xyz_m[2], 0.3);
  EXPECT_DOUBLE_EQ(imu.rpy_rad[0], kPi);
  EXPECT_DOUBLE_EQ(imu.rpy_rad[2], 0.5 * kPi);
  EXPECT_EQ(imu.temperature_c, 40.0);
  EXPECT_EQ(imu.vibration_accel_mps2, 0.4);
  EXPECT_DOUBLE_EQ(imu.vibration_gyro_rad_s, 2.0 * kDeg);
  EXPECT_EQ(imu.vibration_speed_mps, 0.5);
}

TEST(DriveScenario, UnknownKeysAreErrorsWithLineColumnAndSuggestion) {
  const std::string e = load_error(R"(seed = 1
[[path]]
type = "straight"
lenght_m = 3.0
speed_mps = 1.0
[robot]
left_nodes = [1]
right_nodes = [2]
trackwidth_m = 0.5
[imu]
colour = "blue"
)");
  EXPECT_NE(e.find("t.toml:4:1: path[0].lenght_m: unknown key (did you mean 'length_m'?)"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:9:1: robot.trackwidth_m: unknown key (did you mean 'track_width_m'?)"), std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:11:1: imu.colour: unknown key"), std::string::npos) << e;
  // The misspelt length leaves the straight without one: said too.
  EXPECT_NE(e.find("path[0].length_m: missing: give 'length_m' or 'duration_s'"), std::string::npos) << e;
}

TEST(DriveScenario, WrongTypesAreErrorsAtTheValue) {
  const std::string e = load_error(R"(seed = "one"
[[path]]
type = "straight"
length_m = "far"
speed_mps = 1.0
[robot]
left_nodes = [1.5]
right_nodes = 2
encoder_signed = 1
)");
  EXPECT_NE(e.find("t.toml:1:8: seed: expected integer, got string"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:4:12: path[0].length_m: expected float, got string"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:7:15: robot.left_nodes[0]: expected integer, got float"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:8:15: robot.right_nodes: expected array, got integer"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:9:18: robot.encoder_signed: expected boolean, got integer"), std::string::npos) << e;
}

TEST(DriveScenario, OutOfRangeValuesAreErrors) {
  const std::string e = load_error(R"([limits]
max_accel_mps2 = -1.0
[[path]]
type = "arc"
radius_m = 2.0
angle_deg = 0.0
speed_mps = 50.0
[robot]
encoder_bits = 40
left_nodes = [0]
right_nodes = [2]
[imu]
gyro_range_dps = 300
address = 0x80
vibration_speed_mps = 0.0
vibration_accel_mps2 = -0.3
)");
  EXPECT_NE(e.find("t.toml:2:18: limits.max_accel_mps2: must be > 0 and <= 20 m/s^2, got -1"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:6:13: path[0].angle_deg: must be non-zero"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:7:13: path[0].speed_mps: must be > 0 and <= 20 m/s, got 50"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:9:16: robot.encoder_bits: must be between 8 and 32, got 40"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:10:15: robot.left_nodes[0]: a CANopen node id is 1..127, got 0"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:13:18: imu.gyro_range_dps: must be 250, 500, 1000 or 2000, got 300"), std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:14:11: imu.address: must be between 8 and 119, got 128"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:15:23: imu.vibration_speed_mps: must be > 0 and <= 10 m/s, got 0"), std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:16:24: imu.vibration_accel_mps2: must be 0..20 m/s^2 (a Jackal driving: about 0.3), got "
                   "-0.3"),
            std::string::npos)
      << e;
}

TEST(DriveScenario, InconsistentEntriesAreErrors) {
  const std::string e = load_error(R"([[path]]
type = "straight"
length_m = 2.0
duration_s = 2.0
speed_mps = 1.0
[[path]]
type = "hover"
[robot]
left_nodes = [1, 3]
right_nodes = [1]
[[slip.episode]]
start_s = 1.0
duration_s = 1.0
wheel = "left_front"
fraction = 0.2
[[dropout]]
node = 9
start_s = 1.0
duration_s = 1.0
)");
  EXPECT_NE(e.find("t.toml:4:1: path[0].duration_s: give either 'length_m' or 'duration_s', not both"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:7:8: path[1].type: must be one of 'straight', 'arc', 'spin', 'figure_eight', 'stop'"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:9:1: robot.left_nodes: expected 1 node id for this kinematics, got 2"), std::string::npos)
      << e;
  EXPECT_NE(e.find("episode[0].wheel: must be 'left', 'right' or 'all'"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:17:8: dropout[0].node: no wheel of [robot] has node id 9"), std::string::npos) << e;
}

TEST(DriveScenario, DuplicateNodesAndOverlappingDropoutsAreErrors) {
  const std::string e = load_error(R"([[path]]
type = "stop"
duration_s = 5.0
[robot]
left_nodes = [4]
right_nodes = [4]
[[dropout]]
node = 4
start_s = 1.0
duration_s = 2.0
[[dropout]]
node = 4
start_s = 2.5
duration_s = 1.0
)");
  EXPECT_NE(e.find("t.toml:6:1: robot.right_nodes: node id 4 is used twice"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:13:1: dropout[1].start_s: overlaps an earlier dropout of node 4"), std::string::npos) << e;
}

TEST(DriveScenario, ArcTooShortForItsTransitionsIsReportedAtItsEntry) {
  // At 1 m/s into a 0.5 m radius the clothoid is 2 * 1^2 / (pi/2) = 1.27 m
  // long and turns 1.27 * 2 / 2 rad = 73 degrees, on each side: more than
  // the 90 degrees asked.
  const std::string e = load_error(R"([limits]
max_yaw_accel_dps2 = 90.0
[[path]]
type = "straight"
length_m = 5.0
speed_mps = 1.0
[[path]]
type = "arc"
radius_m = 0.5
angle_deg = 90.0
speed_mps = 1.0
[[path]]
type = "straight"
length_m = 5.0
speed_mps = 1.0
)" + kRobot);
  EXPECT_NE(e.find("t.toml:8:1: path[1]: its curvature transitions alone turn the robot by 145.9 deg"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("raise [limits] max_yaw_accel_dps2"), std::string::npos) << e;
}

TEST(DriveScenario, DurationShorterThanThePathIsAnError) {
  // 10 m at 1 m/s from rest to rest at 0.5 m/s^2: 2 s ramps, 8 m cruise: 12 s.
  const std::string e = load_error(R"(duration_s = 10.0
[[path]]
type = "straight"
length_m = 10.0
speed_mps = 1.0
)" + kRobot);
  EXPECT_NE(e.find("t.toml:1:14: duration_s: the path takes 12 s with these speeds and limits"), std::string::npos)
      << e;
}

TEST(DriveScenario, EmptyPathNeedsADuration) {
  EXPECT_NE(load_error(kRobot).find("duration_s: the path is empty"), std::string::npos);
  const DriveScenario sc = load_ok("duration_s = 5.0\n" + kRobot);
  EXPECT_TRUE(sc.path.empty());
}

TEST(DriveScenario, SyntaxErrorsAndUnreadableFiles) {
  const std::string e = load_error("seed = \n");
  EXPECT_EQ(e.rfind("t.toml:1:", 0), 0u) << e;
  DriveScenario sc;
  std::string error;
  EXPECT_FALSE(load_drive_scenario("/nonexistent/scenario.toml", &sc, &error));
  EXPECT_EQ(error, "/nonexistent/scenario.toml: cannot read the scenario: No such file or directory");
}

}  // namespace drive_scenario_test
}  // namespace rtfuse::sim

namespace rtfuse::sim {
namespace drive_scenario_test {

TEST(DriveScenario, GnssReceiverAndItsOutages) {
  const std::string path = "[[path]]\ntype = \"straight\"\nlength_m = 10.0\nspeed_mps = 1.0\n" + kRobot;
  EXPECT_FALSE(load_ok(path).gnss.enabled);
  const DriveScenario sc = load_ok(path + R"(
[gnss]
rate_hz = 10.0
latitude_deg = -33.86
longitude_deg = 151.21
bias_sigma_m = 0.5
antenna_xyz_m = [0.1, 0.0, 1.2]
[[gnss.outage]]
start_s = 3.0
duration_s = 2.0
)");
  EXPECT_TRUE(sc.gnss.enabled);
  EXPECT_EQ(sc.gnss.rate_hz, 10.0);
  EXPECT_EQ(sc.gnss.latitude_deg, -33.86);
  EXPECT_EQ(sc.gnss.bias_sigma_m, 0.5);
  EXPECT_EQ(sc.gnss.antenna_xyz_m[2], 1.2);
  ASSERT_EQ(sc.gnss.outage_count, 1);
  EXPECT_EQ(sc.gnss.outages[0].start_s, 3.0);
  EXPECT_NE(load_error(path + "[gnss]\nlatitude_deg = 89.0\n").find("gnss.latitude_deg: must be within -84..84"),
            std::string::npos);
  EXPECT_NE(load_error(path + "[gnss]\nrate = 5.0\n").find("gnss.rate: unknown key (did you mean 'rate_hz'?)"), std::string::npos)
      << load_error(path + "[gnss]\nrate = 5.0\n");
  EXPECT_NE(load_error(path + "[gnss]\n[[gnss.outage]]\nstart_s = 1.0\n").find("duration_s"), std::string::npos);
}


// --- a commanded drive: [drive], [base], [[goal]] ----------------------------------

TEST(DriveScenario, CommandedDriveReadsItsBaseAndGoals) {
  const DriveScenario sc = load_ok(R"(duration_s = 90.0
[drive]
mode = "commanded"
[base]
max_wheel_speed_mps = 1.5
max_wheel_accel_mps2 = 2.0
command_latency_s = 0.05
command_timeout_s = 0.25
[[goal]]
x_m = 3.0
y_m = -1.5
[[goal]]
x_m = -2.0
y_m = 4.0
yaw_deg = -90.0
tolerance_m = 0.1
)" + kRobot);
  EXPECT_EQ(sc.mode, DriveMode::kCommanded);
  EXPECT_EQ(sc.duration_s, 90.0);
  EXPECT_TRUE(sc.path.empty());
  EXPECT_EQ(sc.base.max_wheel_speed_mps, 1.5);
  EXPECT_EQ(sc.base.max_wheel_accel_mps2, 2.0);
  EXPECT_EQ(sc.base.command_latency_s, 0.05);
  EXPECT_EQ(sc.base.command_timeout_s, 0.25);
  ASSERT_EQ(sc.goals.size(), 2u);
  EXPECT_EQ(sc.goals[0].x_m, 3.0);
  EXPECT_EQ(sc.goals[0].y_m, -1.5);
  EXPECT_FALSE(sc.goals[0].has_yaw);
  EXPECT_EQ(sc.goals[0].tolerance_m, 0.3);  // the default
  EXPECT_EQ(sc.goals[0].line, 10);
  EXPECT_TRUE(sc.goals[1].has_yaw);
  EXPECT_DOUBLE_EQ(sc.goals[1].yaw_rad, -0.5 * kPi);
  EXPECT_EQ(sc.goals[1].tolerance_m, 0.1);

  // The defaults, and a scripted drive stays one.
  const DriveScenario bare = load_ok("duration_s = 5.0\n[drive]\nmode = \"commanded\"\n" + kRobot);
  EXPECT_EQ(bare.base.max_wheel_speed_mps, 1.0);
  EXPECT_EQ(bare.base.max_wheel_accel_mps2, 1.0);
  EXPECT_EQ(bare.base.command_latency_s, 0.02);
  EXPECT_EQ(bare.base.command_timeout_s, 0.5);
  EXPECT_TRUE(bare.goals.empty());
  EXPECT_EQ(load_ok("duration_s = 5.0\n" + kRobot).mode, DriveMode::kPath);
  EXPECT_EQ(load_ok("duration_s = 5.0\n[drive]\nmode = \"path\"\n" + kRobot).mode, DriveMode::kPath);
}

TEST(DriveScenario, CommandedDriveNeedsADurationAndNoPath) {
  const std::string e = load_error(R"([drive]
mode = "commanded"
[[path]]
type = "straight"
length_m = 3.0
speed_mps = 1.0
)" + kRobot);
  EXPECT_NE(e.find("t.toml:2:8: duration_s: missing: a commanded drive needs a duration_s"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:4:1: path: a commanded drive ([drive] mode = 'commanded') follows velocity commands, "
                   "not a scripted path"),
            std::string::npos)
      << e;
  EXPECT_NE(load_error("[drive]\nmode = \"remote\"\n" + kRobot)
                .find("t.toml:2:8: drive.mode: must be one of 'path', 'commanded', got 'remote'"),
            std::string::npos);
}

TEST(DriveScenario, BaseAndGoalErrorsAreReportedAtTheirKeys) {
  const std::string e = load_error(R"(duration_s = 60.0
[drive]
mode = "commanded"
[base]
max_wheel_speed_mps = 0.0
max_wheel_accel_mps2 = 100.0
command_latency_s = 0.0
command_timeout_s = -1.0
max_speed = 1.0
[[goal]]
x_m = 50.0
y_m = nan
[[goal]]
x_m = 2.5
y_m = 3.0
yaw_deg = 400.0
tolerance_m = 0.0
[[goal]]
x_m = 2.5
y_m = 3.3
[[goal]]
y_m = 1.0
heading_deg = 10.0
[[obstacle]]
x_m = 2.5
y_m = 3.0
size_x_m = 0.3
size_y_m = 0.3
[[obstacle]]
x_m = 0.4
y_m = 0.0
size_x_m = 0.3
size_y_m = 0.3
)" + kRobot);
  EXPECT_NE(e.find("t.toml:5:23: base.max_wheel_speed_mps: must be > 0 and <= 10 m/s, got 0"), std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:6:24: base.max_wheel_accel_mps2: must be > 0 and <= 50 m/s^2, got 100"), std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:7:21: base.command_latency_s: must be > 0 and <= 1 s"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:8:21: base.command_timeout_s: must be > 0 and <= 60 s, got -1"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:9:1: base.max_speed: unknown key"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:11:7: goal[0].x_m: must be within the drive area's x -6..18.5 m, got 50"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:12:7: goal[0].y_m: must be within the drive area's y -6.5..19 m, got nan"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:16:11: goal[1].yaw_deg: must be within -360..360 deg, got 400"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:17:15: goal[1].tolerance_m: must be > 0 and <= 10 m, got 0"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:14:1: goal[1].x_m: the goal is inside obstacle[0]"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:19:1: goal[2].x_m: the goal is 0.15 m from obstacle[0]; the robot needs 0.35 m"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("t.toml:21:1: goal[3].x_m: missing required key"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:23:1: goal[3].heading_deg: unknown key"), std::string::npos) << e;
  // The robot starts at the origin, 0.25 m from the second box.
  EXPECT_NE(e.find("obstacle[1]: the robot starts at the origin, 0.25 m from this obstacle; it needs 0.35 m"),
            std::string::npos)
      << e;
}

TEST(DriveScenario, BaseAndGoalsBelongToACommandedDrive) {
  const std::string e = load_error(R"([[path]]
type = "straight"
length_m = 3.0
speed_mps = 1.0
[base]
max_wheel_speed_mps = 1.0
[[goal]]
x_m = 1.0
y_m = 1.0
)" + kRobot);
  EXPECT_NE(e.find("t.toml:5:2: base: only a commanded drive has a [base]"), std::string::npos) << e;
  EXPECT_NE(e.find("t.toml:8:1: goal: goals are for the navigator of a commanded drive"), std::string::npos) << e;
}

TEST(DriveScenario, ObstacleGoalsIsTheObstacleCourseDrivenToGoals) {
  DriveScenario goals, course;
  std::string error;
  ASSERT_TRUE(load_drive_scenario(RTFUSE_SOURCE_DIR "/config/scenarios/obstacle_goals.toml", &goals, &error)) << error;
  ASSERT_TRUE(load_drive_scenario(RTFUSE_SOURCE_DIR "/config/scenarios/obstacles.toml", &course, &error)) << error;
  EXPECT_EQ(goals.mode, DriveMode::kCommanded);
  EXPECT_EQ(goals.duration_s, 240.0);
  EXPECT_TRUE(goals.path.empty());
  ASSERT_EQ(goals.goals.size(), 10u);
  ASSERT_EQ(goals.obstacles.size(), course.obstacles.size());
  for (std::size_t i = 0; i < course.obstacles.size(); ++i) {
    EXPECT_EQ(goals.obstacles[i].x, course.obstacles[i].x);
    EXPECT_EQ(goals.obstacles[i].y, course.obstacles[i].y);
    EXPECT_EQ(goals.obstacles[i].size_x, course.obstacles[i].size_x);
    EXPECT_EQ(goals.obstacles[i].size_y, course.obstacles[i].size_y);
    EXPECT_EQ(goals.obstacles[i].height, course.obstacles[i].height);
  }
  EXPECT_EQ(goals.robot.track_width_m, course.robot.track_width_m);
  EXPECT_EQ(goals.seed, course.seed);
  // One goal beyond the narrow passage (the blocks either side of x = 8,
  // y 4..6), reached from the goal before it, below the passage.
  bool through_passage = false;
  for (std::size_t i = 1; i < goals.goals.size(); ++i) {
    const DriveGoal& a = goals.goals[i - 1];
    const DriveGoal& b = goals.goals[i];
    through_passage = through_passage || (a.y_m < 4.0 && b.y_m > 6.0 && a.x_m > 7.4 && a.x_m < 8.6 &&
                                          b.x_m > 7.4 && b.x_m < 8.6);
  }
  EXPECT_TRUE(through_passage);
  // Some goals lie behind a pillar: the straight line from the goal before
  // passes closer to a pillar than the robot's half track.
  int behind_pillar = 0;
  for (std::size_t i = 1; i < goals.goals.size(); ++i) {
    const DriveGoal& a = goals.goals[i - 1];
    const DriveGoal& b = goals.goals[i];
    for (int p = 0; p < 3; ++p) {  // the three pillars come first
      const ObstacleBox& o = goals.obstacles[static_cast<std::size_t>(p)];
      const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
      const double u = std::clamp(((o.x - a.x_m) * dx + (o.y - a.y_m) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
      const double ex = a.x_m + u * dx - o.x, ey = a.y_m + u * dy - o.y;
      if (std::sqrt(ex * ex + ey * ey) < 0.5 * goals.robot.track_width_m + 0.5 * o.size_x) ++behind_pillar;
    }
  }
  EXPECT_GE(behind_pillar, 3);
  // Back home at the end.
  EXPECT_EQ(goals.goals.back().x_m, 0.0);
  EXPECT_EQ(goals.goals.back().y_m, 0.0);
}

}  // namespace drive_scenario_test
}  // namespace rtfuse::sim
