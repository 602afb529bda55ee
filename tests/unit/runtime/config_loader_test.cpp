#include "runtime/config/config_loader.hpp"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

namespace rtfuse {
namespace config_loader_test {

// gtest only (the runtime tests do not link gmock).
::testing::AssertionResult StartsWith(const std::string& s, const std::string& prefix) {
  if (s.compare(0, prefix.size(), prefix) == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << s << "' does not start with '" << prefix << "'";
}

ConfigLoadResult load(std::string_view text) { return load_config_string(text, "test.toml"); }

std::string all_errors(const ConfigLoadResult& r) {
  std::string s;
  for (const ConfigError& e : r.errors) s += e.to_string() + "\n";
  return s;
}

// The one error a snippet must produce, with its position and key checked
// through to_string so the user-visible format is what is tested.
std::string single_error(const ConfigLoadResult& r) {
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.errors.size(), 1u) << all_errors(r);
  return r.errors.empty() ? std::string() : r.errors.front().to_string();
}

const RuntimeConfig& ok_config(const ConfigLoadResult& r) {
  EXPECT_TRUE(r.errors.empty()) << all_errors(r);
  static const RuntimeConfig kEmpty{};
  return r.config ? *r.config : kEmpty;
}

constexpr const char* kImuFusesYaw =
    "config = [false, false, false, false, false, true, false, false, false, false, false, true, "
    "false, false, false]\n";

// A valid [[sensor]] block to append to error snippets.
std::string sensor(std::string_view name, std::string_view type, std::string_view channel,
                   std::string_view extra = "", std::string_view config = kImuFusesYaw) {
  return "[[sensor]]\nname = \"" + std::string(name) + "\"\ntype = \"" + std::string(type) +
         "\"\nchannel = \"" + std::string(channel) + "\"\n" + std::string(config) + std::string(extra);
}

// `key = [` then the 225 numbers, one matrix row per line.
std::string full_matrix(std::string_view key, const est::StateMatrix& m) {
  std::string s = std::string(key) + " = [\n";
  for (int r = 0; r < est::kStateSize; ++r) {
    s += "  ";
    for (int c = 0; c < est::kStateSize; ++c) s += std::to_string(m(r, c)) + ", ";
    s += "\n";
  }
  return s + "]\n";
}

// ---------------------------------------------------------------- valid input

// Follows "[filter]" and a 225-element process_noise_covariance.
constexpr const char* kFullConfigRest = R"(
frequency = 100
sensor_timeout = 0.25
two_d_mode = true
odom_frame = "odom"
base_link_frame = "base_footprint"
map_frame = "map"
world_frame = "map"
initial_estimate_covariance = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15]
dynamic_process_noise_covariance = true
initial_state = [1, 2, 0, 0, 0, 0.5, 0, 0, 0, 0, 0, 0, 0, 0, 0]
max_variance = 100.0
smooth_lagged_data = true
history_length = 2
gravitational_acceleration = 9.81
yaw_conflict_gate = inf

[realtime]
lock_memory = true
priority = 80
io_priority = 70
cpu = 2
require = true

[lcm]
url = "memq://"

[publish]
odometry_channel = "out/odom"
odometry_rate = 25.5
pose_rate = 0
set_pose_channel = "in/set_pose"
publish_tf = false

[[sensor]]
name = "odom0"
type = "odometry"
channel = "wheel/odom"
config = [false, false, false, false, false, false,
          true,  true,  false, false, false, true,
          false, false, false]
queue_size = 3
twist_rejection_threshold = 4

[[sensor]]
name = "imu0"
type = "imu"
channel = "imu/data"
config = [false, false, false, true, true, true,
          false, false, false, true, true, true,
          true,  true,  true]
relative = true
pose_rejection_threshold = 3.5
linear_acceleration_rejection_threshold = inf
remove_gravitational_acceleration = true

[[static_transform]]
parent = "base_footprint"
child = "imu_link"
translation = [0.1, -0.2, 0.3]
rpy = [0, 0, 1.5707963267948966]

[[static_transform]]
parent = "base_footprint"
child = "gps"
translation = [0, 0, 1]
quaternion = [0, 0, 0, 1.0005]

[sim]
enabled = true
seed = 42
radius = 5
speed = 2.5
imu_rate = 200
odom_rate = 20
imu_channel = "sim/imu"
odom_channel = "sim/odom"
truth_channel = "sim/truth"
gyro_noise = 0.001
gyro_bias = 0
accel_noise = 0.1
accel_bias = 0.2
orientation_noise = 0.3
yaw_error = 0.004
yaw_error_time = 12.5
odom_speed_noise = 0.05
odom_yaw_rate_noise = 0.06
wheel_slip = 0.1
)";

TEST(ConfigLoader, FullConfigParsesToTheRightValues) {
  est::StateMatrix q = est::StateMatrix::Identity();
  q(0, 1) = q(1, 0) = 0.25;
  q(5, 14) = q(14, 5) = -0.125;
  const auto r = load("[filter]\n" + full_matrix("process_noise_covariance", q) + kFullConfigRest);
  const RuntimeConfig& c = ok_config(r);
  EXPECT_EQ(c.source, "test.toml");
  EXPECT_DOUBLE_EQ(c.rate_hz, 100.0);  // integer accepted for a float
  EXPECT_DOUBLE_EQ(c.filter.sensor_timeout_s, 0.25);
  EXPECT_TRUE(c.filter.two_d_mode);
  EXPECT_EQ(c.base_link_frame, "base_footprint");
  EXPECT_EQ(c.world_frame, "map");
  EXPECT_DOUBLE_EQ(c.filter.process_noise(0, 1), 0.25);  // row-major 225
  EXPECT_DOUBLE_EQ(c.filter.process_noise(14, 5), -0.125);
  EXPECT_DOUBLE_EQ(c.filter.process_noise(3, 3), 1.0);
  EXPECT_DOUBLE_EQ(c.filter.process_noise(2, 3), 0.0);
  EXPECT_DOUBLE_EQ(c.filter.initial_covariance(14, 14), 15.0);  // 15 = diagonal
  EXPECT_DOUBLE_EQ(c.filter.initial_covariance(0, 1), 0.0);
  EXPECT_TRUE(c.filter.dynamic_process_noise);
  EXPECT_TRUE(c.filter.has_initial_state);
  EXPECT_DOUBLE_EQ(c.filter.initial_state(est::kYaw), 0.5);
  EXPECT_DOUBLE_EQ(c.filter.max_variance, 100.0);
  EXPECT_TRUE(c.filter.smooth_lagged_data);
  EXPECT_DOUBLE_EQ(c.filter.history_length_s, 2.0);
  EXPECT_DOUBLE_EQ(c.filter.gravity, 9.81);
  EXPECT_TRUE(std::isinf(c.filter.yaw_conflict_gate_sigma));

  EXPECT_TRUE(c.realtime.lock_memory);
  EXPECT_EQ(c.realtime.priority, 80);
  EXPECT_EQ(c.realtime.io_priority, 70);
  EXPECT_EQ(c.realtime.cpu, 2);
  EXPECT_TRUE(c.realtime.require);
  EXPECT_EQ(c.lcm_url, "memq://");
  EXPECT_EQ(c.publish.odometry_channel, "out/odom");
  EXPECT_DOUBLE_EQ(c.publish.odometry_rate_hz, 25.5);
  EXPECT_DOUBLE_EQ(c.publish.pose_rate_hz, 0.0);
  EXPECT_EQ(c.publish.pose_channel, "rtfuse/pose");  // untouched default
  EXPECT_EQ(c.publish.set_pose_channel, "in/set_pose");
  EXPECT_FALSE(c.publish.publish_tf);

  ASSERT_EQ(c.num_sensors, 2);
  const SensorConfig& odom = c.sensors[0];
  EXPECT_EQ(odom.name, "odom0");
  EXPECT_EQ(odom.channel, "wheel/odom");
  EXPECT_EQ(odom.params.kind, est::SensorKind::kOdometry);
  EXPECT_EQ(odom.params.update_mask, est::mask_bit(est::kVx) | est::mask_bit(est::kVy) | est::mask_bit(est::kVyaw));
  EXPECT_EQ(odom.params.queue_size, 3);
  EXPECT_DOUBLE_EQ(odom.params.twist_rejection_threshold, 4.0);
  EXPECT_TRUE(std::isinf(odom.params.pose_rejection_threshold));
  const SensorConfig& imu = c.sensors[1];
  EXPECT_EQ(imu.params.kind, est::SensorKind::kImu);
  EXPECT_EQ(imu.params.update_mask, est::kOrientationMask | est::kAngularVelocityMask | est::kAccelerationMask);
  EXPECT_TRUE(imu.params.relative);
  EXPECT_FALSE(imu.params.differential);
  EXPECT_EQ(imu.params.queue_size, 10);
  EXPECT_DOUBLE_EQ(imu.params.pose_rejection_threshold, 3.5);
  EXPECT_TRUE(std::isinf(imu.params.linear_acceleration_rejection_threshold));
  EXPECT_TRUE(imu.params.remove_gravitational_acceleration);

  ASSERT_EQ(c.num_static_transforms, 2);
  const StaticTransformConfig& t = c.static_transforms[0];
  EXPECT_EQ(t.parent, "base_footprint");
  EXPECT_EQ(t.child, "imu_link");
  EXPECT_TRUE(t.parent_T_child.translation.isApprox(Eigen::Vector3d(0.1, -0.2, 0.3)));
  // yaw = +90 deg: the child's x axis is the parent's y axis.
  EXPECT_TRUE((t.parent_T_child.rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  const StaticTransformConfig& g = c.static_transforms[1];
  EXPECT_NEAR(g.parent_T_child.rotation.norm(), 1.0, 1e-15);  // 1.0005 normalised
  EXPECT_NEAR(g.parent_T_child.rotation.w(), 1.0, 1e-15);

  EXPECT_TRUE(c.sim.enabled);
  EXPECT_EQ(c.sim.seed, 42u);
  EXPECT_DOUBLE_EQ(c.sim.figure_eight_radius_m, 5.0);
  EXPECT_DOUBLE_EQ(c.sim.speed_mps, 2.5);
  EXPECT_DOUBLE_EQ(c.sim.imu_rate_hz, 200.0);
  EXPECT_DOUBLE_EQ(c.sim.odom_rate_hz, 20.0);
  EXPECT_EQ(c.sim.imu_channel, "sim/imu");
  EXPECT_EQ(c.sim.odom_channel, "sim/odom");
  EXPECT_EQ(c.sim.truth_channel, "sim/truth");
  EXPECT_DOUBLE_EQ(c.sim.gyro_noise_rad_s, 0.001);
  EXPECT_DOUBLE_EQ(c.sim.gyro_bias_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(c.sim.accel_noise_mps2, 0.1);
  EXPECT_DOUBLE_EQ(c.sim.accel_bias_mps2, 0.2);
  EXPECT_DOUBLE_EQ(c.sim.orientation_noise_rad, 0.3);
  EXPECT_DOUBLE_EQ(c.sim.yaw_error_rad, 0.004);
  EXPECT_DOUBLE_EQ(c.sim.yaw_error_time_s, 12.5);
  EXPECT_DOUBLE_EQ(c.sim.odom_speed_noise_mps, 0.05);
  EXPECT_DOUBLE_EQ(c.sim.odom_yaw_rate_noise_rad_s, 0.06);
  EXPECT_DOUBLE_EQ(c.sim.wheel_slip, 0.1);
}

TEST(ConfigLoader, DefaultsWhenSectionsAreAbsent) {
  const auto r = load("");
  const RuntimeConfig& c = ok_config(r);
  EXPECT_DOUBLE_EQ(c.rate_hz, 200.0);
  EXPECT_DOUBLE_EQ(c.filter.sensor_timeout_s, 1.0 / 200.0);
  EXPECT_FALSE(c.filter.two_d_mode);
  EXPECT_EQ(c.world_frame, "odom");
  EXPECT_EQ(c.odom_frame, "odom");
  EXPECT_EQ(c.base_link_frame, "base_link");
  EXPECT_EQ(c.map_frame, "map");
  const double q[] = {0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};
  for (int i = 0; i < est::kStateSize; ++i) {
    EXPECT_DOUBLE_EQ(c.filter.process_noise(i, i), q[i]) << i;
    EXPECT_DOUBLE_EQ(c.filter.initial_covariance(i, i), 1e-9) << i;
  }
  EXPECT_DOUBLE_EQ(c.filter.process_noise(0, 1), 0.0);
  EXPECT_FALSE(c.filter.has_initial_state);
  EXPECT_DOUBLE_EQ(c.filter.max_variance, 1e6);
  EXPECT_DOUBLE_EQ(c.filter.gravity, 9.80665);
  EXPECT_DOUBLE_EQ(c.filter.yaw_conflict_gate_sigma, 5.0);
  EXPECT_EQ(c.lcm_url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(c.realtime.priority, 0);
  EXPECT_EQ(c.realtime.io_priority, 0);
  EXPECT_EQ(c.realtime.cpu, -1);
  EXPECT_EQ(c.publish.diagnostics_channel, "rtfuse/diagnostics");
  EXPECT_DOUBLE_EQ(c.publish.state_rate_hz, 10.0);
  EXPECT_EQ(c.num_sensors, 0);
  EXPECT_EQ(c.num_static_transforms, 0);
  EXPECT_FALSE(c.sim.enabled);
  EXPECT_DOUBLE_EQ(c.sim.figure_eight_radius_m, 3.0);
  EXPECT_EQ(c.sim.imu_channel, "imu/data");
}

TEST(ConfigLoader, DefaultsFollowTheKeysTheyDependOn) {
  const auto r = load("[filter]\nfrequency = 50\nodom_frame = \"odo\"\n");
  const RuntimeConfig& c = ok_config(r);
  EXPECT_DOUBLE_EQ(c.filter.sensor_timeout_s, 0.02);  // 1 / frequency
  EXPECT_EQ(c.world_frame, "odo");                     // = odom_frame
}

TEST(ConfigLoader, SensorDefaults) {
  const auto r = load(sensor("imu0", "imu", "imu/data"));
  const RuntimeConfig& c = ok_config(r);
  ASSERT_EQ(c.num_sensors, 1);
  const est::SensorParams& p = c.sensors[0].params;
  EXPECT_EQ(p.update_mask, est::mask_bit(est::kYaw) | est::mask_bit(est::kVyaw));
  EXPECT_FALSE(p.differential);
  EXPECT_FALSE(p.relative);
  EXPECT_EQ(p.queue_size, 10);
  EXPECT_TRUE(std::isinf(p.pose_rejection_threshold));
  EXPECT_TRUE(std::isinf(p.twist_rejection_threshold));
  EXPECT_FALSE(p.remove_gravitational_acceleration);
}

TEST(ConfigLoader, InputLimitsFromTheNetwork) {
  // Defaults: set_pose ignored, 4 KiB messages, a sensor's rate what the
  // loop drains (2 x queue_size per tick at [filter] frequency).
  {
    const auto r = load("[filter]\nfrequency = 50\n" + sensor("imu0", "imu", "imu/data", "queue_size = 4\n"));
    const RuntimeConfig& c = ok_config(r);
    EXPECT_FALSE(c.publish.accept_set_pose);
    EXPECT_EQ(c.lcm_max_message_bytes, 4096);
    EXPECT_DOUBLE_EQ(c.sensors[0].max_rate_hz, 400.0);
  }
  const auto r = load("[lcm]\nmax_message_bytes = 1024\n[publish]\naccept_set_pose = true\n" +
                      sensor("imu0", "imu", "imu/data", "max_rate = 250.0\n"));
  const RuntimeConfig& c = ok_config(r);
  EXPECT_TRUE(c.publish.accept_set_pose);
  EXPECT_EQ(c.lcm_max_message_bytes, 1024);
  EXPECT_DOUBLE_EQ(c.sensors[0].max_rate_hz, 250.0);

  EXPECT_EQ(single_error(load("[lcm]\nmax_message_bytes = 100\n")),
            "test.toml:2:21: lcm.max_message_bytes: must be between 256 and 1048576, got 100");
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "max_rate = 0.0\n"))),
            "test.toml:6:12: sensor[0].max_rate: must be > 0 and <= 1e6 Hz, got 0");
  // A driver-fed sensor has no channel to limit (the other errors: the
  // [wheel_odometry] keys this snippet leaves out).
  const std::string driver = all_errors(load(
      "[[sensor]]\nname = \"w\"\ntype = \"twist\"\nsource = \"wheel_odometry\"\nconfig = [false, false, false, "
      "false, false, false, true, false, false, false, false, false, false, false, false]\nmax_rate = 10.0\n"));
  EXPECT_NE(driver.find("test.toml:6:1: sensor[0].max_rate: not used with source = 'wheel_odometry' (the driver feeds"),
            std::string::npos)
      << driver;
}

TEST(ConfigLoader, ExampleRobotConfigLoads) {
  const std::string path = RTFUSE_SOURCE_DIR "/config/example_robot.toml";
  const auto r = load_config_file(path);
  const RuntimeConfig& c = ok_config(r);
  EXPECT_EQ(c.source, path);
  ASSERT_EQ(c.num_sensors, 2);
  EXPECT_EQ(c.sensors[0].params.kind, est::SensorKind::kOdometry);
  EXPECT_EQ(c.sensors[0].params.update_mask,
            est::mask_bit(est::kVx) | est::mask_bit(est::kVy) | est::mask_bit(est::kVyaw));
  EXPECT_EQ(c.sensors[1].params.kind, est::SensorKind::kImu);
  ASSERT_EQ(c.num_static_transforms, 1);
  EXPECT_EQ(c.static_transforms[0].parent, "base_link");
  EXPECT_EQ(c.static_transforms[0].child, "imu_link");
  EXPECT_TRUE((c.static_transforms[0].parent_T_child.rotation * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

// --------------------------------------------------------------- error classes

TEST(ConfigLoader, UnknownKeySuggestsTheClosestOne) {
  EXPECT_EQ(single_error(load("[filter]\nprocss_noise_covariance = [1, 2]\n")),
            "test.toml:2:1: filter.procss_noise_covariance: unknown key (did you mean 'process_noise_covariance'?)");
  EXPECT_EQ(single_error(load("[filtr]\nfrequency = 5\n")),
            "test.toml:1:2: filtr: unknown key (did you mean 'filter'?)");
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "  qeueu_size = 3\n"))),
            "test.toml:6:3: sensor[0].qeueu_size: unknown key (did you mean 'queue_size'?)");
  EXPECT_EQ(single_error(load("[realtime]\ncompletely_different = 1\n")),
            "test.toml:2:1: realtime.completely_different: unknown key");
}

TEST(ConfigLoader, WrongTypeNamesExpectedAndActual) {
  EXPECT_EQ(single_error(load("[filter]\ntwo_d_mode = \"yes\"\n")),
            "test.toml:2:14: filter.two_d_mode: expected boolean, got string");
  EXPECT_EQ(single_error(load("[filter]\nfrequency = \"fast\"\n")),
            "test.toml:2:13: filter.frequency: expected float, got string");
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "queue_size = 2.5\n"))),
            "test.toml:6:14: sensor[0].queue_size: expected integer, got float");
  EXPECT_EQ(single_error(load("filter = 3\n")), "test.toml:1:10: filter: expected table, got integer");
  EXPECT_EQ(single_error(load("[filter]\ninitial_state = [0, 0, \"z\", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n")),
            "test.toml:2:24: filter.initial_state[2]: expected float, got string");
}

TEST(ConfigLoader, OutOfRangeSaysRangeAndValue) {
  EXPECT_EQ(single_error(load("[filter]\nfrequency = -5\n")),
            "test.toml:2:13: filter.frequency: must be > 0 and <= 10000 Hz, got -5");
  EXPECT_EQ(single_error(load("[realtime]\npriority = 120\n")),
            "test.toml:2:12: realtime.priority: must be between 0 and 99, got 120");
  // The loop must preempt the threads that feed it, so they may not match or outrank it.
  EXPECT_EQ(single_error(load("[realtime]\npriority = 50\nio_priority = 50\n")),
            "test.toml:3:15: realtime.io_priority: must be below priority (50), got 50: the loop must preempt "
            "the threads that feed it");
  EXPECT_EQ(single_error(load("[realtime]\nio_priority = 10\n")),
            "test.toml:2:15: realtime.io_priority: must be below priority (0), got 10: the loop must preempt "
            "the threads that feed it");
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "queue_size = 0\n"))),
            "test.toml:6:14: sensor[0].queue_size: must be between 1 and 1024, got 0");
  EXPECT_EQ(single_error(load("[sim]\nimu_rate = 0\n")),
            "test.toml:2:12: sim.imu_rate: must be > 0 Hz and finite, got 0");
  EXPECT_EQ(single_error(load("[sim]\ngyro_noise = -0.1\n")),
            "test.toml:2:14: sim.gyro_noise: must be >= 0 and finite, got -0.1");
  EXPECT_EQ(single_error(load("[filter]\nfrequency = nan\n")),
            "test.toml:2:13: filter.frequency: must be > 0 and <= 10000 Hz, got nan");
}

TEST(ConfigLoader, ConfigArrayMustHave15Booleans) {
  const std::string fourteen =
      "config = [false, false, false, false, false, true, false, false, false, false, false, true, false, false]\n";
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "", fourteen))),
            "test.toml:5:1: sensor[0].config: expected 15 booleans "
            "(x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az), got 14");
  const std::string with_int =
      "config = [false, false, false, false, false, 1, false, false, false, false, false, true, false, false, false]\n";
  EXPECT_EQ(single_error(load(sensor("a", "imu", "c", "", with_int))),
            "test.toml:5:46: sensor[0].config[5]: expected boolean, got integer");
}

TEST(ConfigLoader, NonSymmetricCovarianceIsAnErrorAtTheElement) {
  est::StateMatrix m = est::StateMatrix::Identity();
  m(0, 1) = 0.5;
  m(1, 0) = 0.25;
  // Row 1 is on line 4 ("[filter]", key line, row 0); its first element at column 3.
  EXPECT_EQ(single_error(load("[filter]\n" + full_matrix("initial_estimate_covariance", m))),
            "test.toml:4:3: filter.initial_estimate_covariance: not symmetric: [1][0] = 0.25 but [0][1] = 0.5");
}

TEST(ConfigLoader, NonPsdCovarianceIsAnError) {
  est::StateMatrix m = est::StateMatrix::Identity();
  m(0, 1) = m(1, 0) = 2.0;  // eigenvalues of the 2x2 block: 3 and -1
  const std::string e = single_error(load("[filter]\n" + full_matrix("process_noise_covariance", m)));
  EXPECT_TRUE(StartsWith(e, "test.toml:2:1: filter.process_noise_covariance: not positive semi-definite: "
                            "smallest eigenvalue -1"));
  EXPECT_EQ(single_error(load("[filter]\nprocess_noise_covariance = [1, 1, 1, -1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n")),
            "test.toml:2:38: filter.process_noise_covariance[3]: a variance must be >= 0, got -1");
  EXPECT_EQ(single_error(load("[filter]\nprocess_noise_covariance = [1, 1]\n")),
            "test.toml:2:1: filter.process_noise_covariance: expected 15 (diagonal) or 225 (row-major 15x15) "
            "floats, got 2");
}

TEST(ConfigLoader, DuplicateSensorNameAndChannel) {
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "a") + sensor("imu0", "imu", "b"))),
            "test.toml:7:8: sensor[1].name: duplicate sensor name 'imu0' (also sensor[0])");
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "a") + sensor("imu1", "imu", "a"))),
            "test.toml:9:11: sensor[1].channel: channel 'a' is also sensor[0].channel");
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "rtfuse/tf"))),
            "test.toml:4:11: sensor[0].channel: channel 'rtfuse/tf' is also publish.tf_channel");
  EXPECT_EQ(single_error(load("[publish]\npose_channel = \"x\"\nstate_channel = \"x\"\n")),
            "test.toml:3:17: publish.state_channel: channel 'x' is also publish.pose_channel");
}

TEST(ConfigLoader, SensorTypeLimitsItsConfig) {
  const std::string imu_x =
      "config = [true, false, false, false, false, true, false, false, false, false, false, true, false, false, false]\n";
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "c", "", imu_x))),
            "test.toml:5:11: sensor[0].config: type 'imu' cannot provide x "
            "(it provides roll pitch yaw vroll vpitch vyaw ax ay az)");
  const std::string odom_accel =
      "config = [false, false, false, false, false, true, false, false, false, false, false, true, true, true, false]\n";
  EXPECT_TRUE(StartsWith(single_error(load(sensor("odom0", "odometry", "c", "", odom_accel))), "test.toml:5:93: sensor[0].config: type 'odometry' cannot provide ax ay "));
  EXPECT_TRUE(StartsWith(single_error(load(sensor("odom0", "pose", "c"))), "test.toml:5:87: sensor[0].config: type 'pose' cannot provide vyaw "));
  EXPECT_TRUE(StartsWith(single_error(load(sensor("t0", "twist", "c"))), "test.toml:5:46: sensor[0].config: type 'twist' cannot provide yaw "));
  const std::string none =
      "config = [false, false, false, false, false, false, false, false, false, false, false, false, false, false, "
      "false]\n";
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "c", "", none))),
            "test.toml:5:1: sensor[0].config: fuses nothing: at least one entry must be true");
  EXPECT_EQ(single_error(load(sensor("g", "gps", "c"))),
            "test.toml:3:8: sensor[0].type: must be one of odometry, pose, twist, imu, navsat, got 'gps'");
  EXPECT_EQ(single_error(load(sensor("o", "odometry", "c",
                                     "remove_gravitational_acceleration = true\n",
                                     "config = [true, true, false, false, false, false, false, false, false, "
                                     "false, false, false, false, false, false]\n"))),
            "test.toml:6:1: sensor[0].remove_gravitational_acceleration: only valid for type 'imu'");
}

TEST(ConfigLoader, DifferentialAndRelativeTogether) {
  EXPECT_EQ(single_error(load(sensor("imu0", "imu", "c", "differential = true\nrelative = true\n"))),
            "test.toml:7:12: sensor[0].relative: differential and relative cannot both be true");
}

TEST(ConfigLoader, MissingRequiredSensorKeys) {
  const auto r = load("[filter]\n\n[[sensor]]\nname = \"a\"\n");
  ASSERT_EQ(r.errors.size(), 3u) << all_errors(r);
  EXPECT_EQ(r.errors[0].to_string(), "test.toml:3:1: sensor[0].type: missing required key");
  EXPECT_EQ(r.errors[1].to_string(), "test.toml:3:1: sensor[0].channel: missing required key");
  EXPECT_EQ(r.errors[2].to_string(), "test.toml:3:1: sensor[0].config: missing required key");
  EXPECT_EQ(single_error(load("[[sensor]]\ntype = \"imu\"\nchannel = \"c\"\n" + std::string(kImuFusesYaw))),
            "test.toml:1:1: sensor[0].name: missing required key");
}

TEST(ConfigLoader, StaticTransformNeedsExactlyOneRotation) {
  EXPECT_EQ(single_error(load("[[static_transform]]\nparent = \"a\"\nchild = \"b\"\ntranslation = [0, 0, 0]\n"
                              "rpy = [0, 0, 0]\nquaternion = [0, 0, 0, 1]\n")),
            "test.toml:6:1: static_transform[0].quaternion: rpy and quaternion are both given: give exactly one");
  EXPECT_EQ(single_error(load("[[static_transform]]\nparent = \"a\"\nchild = \"b\"\ntranslation = [0, 0, 0]\n")),
            "test.toml:1:1: static_transform[0].rpy: missing rotation: give exactly one of rpy or quaternion");
  EXPECT_EQ(single_error(load("[[static_transform]]\nparent = \"a\"\nchild = \"b\"\ntranslation = [0, 0]\n"
                              "rpy = [0, 0, 0]\n")),
            "test.toml:4:1: static_transform[0].translation: expected 3 floats (x y z), got 2");
  EXPECT_EQ(single_error(load("[[static_transform]]\nparent = \"a\"\nchild = \"a\"\ntranslation = [0, 0, 0]\n"
                              "rpy = [0, 0, 0]\n")),
            "test.toml:3:9: static_transform[0].child: must differ from parent (both 'a')");
  EXPECT_EQ(single_error(load("[[static_transform]]\nparent = \"a\"\nchild = \"b\"\ntranslation = [0, 0, 0]\n"
                              "quaternion = [0, 0, 0, 2]\n")),
            "test.toml:5:14: static_transform[0].quaternion: norm must be within 1e-3 of 1, got 2");
}

TEST(ConfigLoader, WorldFrameMustBeOdomOrMap) {
  EXPECT_EQ(single_error(load("[filter]\nworld_frame = \"earth\"\n")),
            "test.toml:2:15: filter.world_frame: must equal odom_frame ('odom') or map_frame ('map'), got 'earth'");
  EXPECT_EQ(single_error(load("[filter]\nbase_link_frame = \"odom\"\n")),
            "test.toml:2:19: filter.base_link_frame: must differ from odom_frame (both 'odom')");
  EXPECT_EQ(single_error(load("[filter]\nworld_frame = \"map\"\nbase_link_frame = \"map\"\n")),
            "test.toml:3:19: filter.base_link_frame: must differ from map_frame (both 'map')");
}

TEST(ConfigLoader, OtherCrossChecks) {
  EXPECT_EQ(single_error(load("[filter]\nsmooth_lagged_data = true\n")),
            "test.toml:2:22: filter.history_length: must be > 0 s when smooth_lagged_data is true, got 0");
  EXPECT_EQ(single_error(load("[lcm]\nurl = \"239.255.76.67:7667\"\n")),
            "test.toml:2:7: lcm.url: must be '<provider>://...' (udpm://, memq://, file://, ...), got "
            "'239.255.76.67:7667'");
  EXPECT_TRUE(load("[lcm]\nurl = \"tcpq://localhost:7700\"\n").ok());
  EXPECT_EQ(single_error(load("[filter]\nodom_frame = \"" + std::string(64, 'o') + "\"\n")),
            "test.toml:2:14: filter.odom_frame: longer than 63 characters (64)");
  EXPECT_TRUE(load("[filter]\nodom_frame = \"" + std::string(63, 'o') + "\"\n").ok());
  EXPECT_EQ(single_error(load("[filter]\nmap_frame = \"\"\n")), "test.toml:2:13: filter.map_frame: must not be empty");
}

TEST(ConfigLoader, AtMostMaxSensors) {
  std::string text;
  for (int i = 0; i <= kMaxSensors; ++i) {
    text += sensor("s" + std::to_string(i), "imu", "c" + std::to_string(i));
  }
  // Each sensor block is 5 lines, so sensor[16] starts on line 81.
  EXPECT_EQ(single_error(load(text)), "test.toml:81:1: sensor: at most 16 entries, got 17");
}

TEST(ConfigLoader, UnreadableFileNamesPathAndErrno) {
  const auto r = load_config_file("/nonexistent/rtfuse.toml");
  EXPECT_EQ(single_error(r), "/nonexistent/rtfuse.toml: cannot read file: No such file or directory");
  EXPECT_EQ(single_error(load_config_file("/")), "/: cannot read file: Is a directory");
}

TEST(ConfigLoader, TomlSyntaxErrorHasLineAndColumn) {
  const auto r = load("[filter]\nfrequency = 100\ntwo_d_mode = tru\n");
  const std::string e = single_error(r);
  // toml++ stops after "tru" and its newline; the wording is toml++'s own.
  EXPECT_TRUE(StartsWith(e, "test.toml:3:17: Error while parsing boolean"));
  EXPECT_TRUE(r.errors.at(0).key.empty());
  EXPECT_EQ(e.find('\n'), std::string::npos) << "one line per error";
  EXPECT_EQ(single_error(load("[filter]\nprocess_noise_covariance = [1,\n  2,, 3]\n")),
            "test.toml:3:5: Error while parsing array: expected value or closing ']', saw comma");
}

TEST(ConfigLoader, AllErrorsAreReportedTogetherInFileOrder) {
  const auto r = load(
      "[filter]\n"
      "frequency = 0\n"           // 2: out of range
      "two_d_mod = true\n"        // 3: unknown key
      "[realtime]\n"
      "cpu = \"one\"\n" +         // 5: wrong type
      sensor("imu0", "imu", "c", "relative = true\ndifferential = true\n"));  // 6..12
  ASSERT_EQ(r.errors.size(), 4u) << all_errors(r);
  EXPECT_FALSE(r.config.has_value());
  EXPECT_TRUE(StartsWith(r.errors[0].to_string(), "test.toml:2:13: filter.frequency: "));
  EXPECT_TRUE(StartsWith(r.errors[1].to_string(), "test.toml:3:1: filter.two_d_mod: unknown key (did you mean 'two_d_mode'?)"));
  EXPECT_TRUE(StartsWith(r.errors[2].to_string(), "test.toml:5:7: realtime.cpu: expected integer, got string"));
  EXPECT_TRUE(StartsWith(r.errors[3].to_string(), "test.toml:11:12: sensor[0].relative: "));
}

}  // namespace config_loader_test
}  // namespace rtfuse
