// [hardware], [can], [[can.node]], [wheel_odometry], [mpu] and the sensors
// they feed: values land where the drivers read them, and each mistake a
// user can make names its line and key.
#include <string>

#include <gtest/gtest.h>

#include "runtime/config/config_loader.hpp"
#include "runtime/devices/device_registry.hpp"

namespace rtfuse {
namespace hardware_config_test {

std::string all_errors(const ConfigLoadResult& r) {
  std::string s;
  for (const ConfigError& e : r.errors) s += e.to_string() + "\n";
  return s;
}

constexpr const char* kWheelSensor = R"(
[[sensor]]
name = "wheels"
type = "twist"
source = "wheel_odometry"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
)";

constexpr const char* kMpuSensor = R"(
[[sensor]]
name = "imu"
type = "imu"
source = "mpu"
config = [false, false, false, true, true, false, false, false, false, false, false, true, false, false, false]
)";

constexpr const char* kCan = R"(
[can]
interface = "can1"
sync_cob_id = 0x80
heartbeat_timeout = 0.3
[[can.node]]
node_id = 1
side = "left"
[[can.node]]
node_id = 2
side = "right"
sign = -1
position_bits = 16
position_signed = true
)";

constexpr const char* kWheels = R"(
[wheel_odometry]
kinematics = "skid_steer"
track_width = 0.55
wheel_radius = 0.098
counts_per_rev = 1024
gear_ratio = 30
skid_track_factor = 1.6
)";

constexpr const char* kMpu = R"(
[mpu]
device = "/dev/i2c-8"
address = 0x69
model = "mpu9250"
gyro_range = 1000
accel_range = 8
data_ready_chip = "tegra-gpio"
data_ready_line = 160
frame = "imu_link"
[mpu.attitude]
algorithm = "mahony"
kp = 2.0
ki = 0.05
)";

const char* const kImuMount = R"(
[[static_transform]]
parent = "base_link"
child = "imu_link"
translation = [0.1, 0, 0.2]
rpy = [0, 0, 0]
)";

constexpr const char* kStereoSensor = R"(
[[sensor]]
name = "stereo"
type = "twist"
source = "stereo_vo"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
)";

constexpr const char* kCamera = "[camera]\ncalibration = \"SN1.conf\"\n";  // 2 lines

ConfigLoadResult load(const std::string& text) { return load_config_string(text, "hw.toml"); }

TEST(HardwareConfig, FullRobotLandsInTheStructures) {
  const ConfigLoadResult r = load(std::string("[hardware]\nbackend = \"linux\"\n") + kCan + kWheels + kMpu +
                                  kWheelSensor + kMpuSensor + kImuMount);
  ASSERT_TRUE(r.ok()) << all_errors(r);
  const HardwareConfig& hw = r.config->hardware;
  EXPECT_EQ(hw.backend, HalBackend::kLinux);
  EXPECT_TRUE(hw.can.enabled);
  EXPECT_EQ(hw.can.interface.view(), "can1");
  EXPECT_DOUBLE_EQ(hw.can.heartbeat_timeout_s, 0.3);
  ASSERT_EQ(hw.can.num_nodes, 2);
  EXPECT_EQ(hw.can.nodes[1].node_id, 2);
  EXPECT_EQ(hw.can.nodes[1].side, WheelSideConfig::kRight);
  EXPECT_EQ(hw.can.nodes[1].sign, -1);
  EXPECT_EQ(hw.can.nodes[1].position_bits, 16);
  EXPECT_TRUE(hw.can.nodes[1].position_signed);
  EXPECT_EQ(hw.wheel_odometry.kinematics, KinematicsConfig::kSkidSteer);
  EXPECT_DOUBLE_EQ(hw.wheel_odometry.gear_ratio, 30);
  EXPECT_DOUBLE_EQ(hw.wheel_odometry.skid_track_factor, 1.6);
  EXPECT_TRUE(hw.mpu.enabled);
  EXPECT_EQ(hw.mpu.address, 0x69);
  EXPECT_EQ(hw.mpu.model, MpuModelConfig::kMpu9250);
  EXPECT_EQ(hw.mpu.gyro_range_dps, 1000);
  EXPECT_EQ(hw.mpu.data_ready_line, 160);
  EXPECT_EQ(hw.mpu.attitude.algorithm, AttitudeAlgorithmConfig::kMahony);
  EXPECT_DOUBLE_EQ(hw.mpu.attitude.ki, 0.05);
  EXPECT_EQ(source_sensor(*r.config, "wheel_odometry"), 0);
  EXPECT_EQ(source_sensor(*r.config, "mpu"), 1);
  EXPECT_EQ(r.config->sensors[0].source, find_device_source("wheel_odometry"));
  EXPECT_TRUE(r.config->sensors[0].channel.empty());
}

TEST(HardwareConfig, SimScenarioIsRelativeToTheConfigFile) {
  const ConfigLoadResult r = load_config_string(
      std::string("[hardware]\nbackend = \"sim\"\nscenario = \"scenarios/demo.toml\"\n") + kCan + kWheels +
          kWheelSensor,
      "/etc/rtfuse/robot.toml");
  ASSERT_TRUE(r.ok()) << all_errors(r);
  EXPECT_EQ(r.config->hardware.scenario, "/etc/rtfuse/scenarios/demo.toml");
}

struct BadCase {
  const char* name;
  std::string text;
  const char* error;  // the one expected error, as printed
};

class HardwareConfigError : public ::testing::TestWithParam<BadCase> {};

TEST_P(HardwareConfigError, NamesLineAndKey) {
  const ConfigLoadResult r = load(GetParam().text);
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 1u) << all_errors(r);
  EXPECT_EQ(r.errors[0].to_string(), GetParam().error);
}

const std::string kLinux = "[hardware]\nbackend = \"linux\"\n";  // 2 lines

INSTANTIATE_TEST_SUITE_P(
    Cases, HardwareConfigError,
    ::testing::Values(
        BadCase{"UnknownBackend", "[hardware]\nbackend = \"vcan\"\n",
                "hw.toml:2:11: hardware.backend: must be one of none, linux, sim, got 'vcan'"},
        BadCase{"SimWithoutScenario", "[hardware]\nbackend = \"sim\"\n",
                "hw.toml:1:1: hardware.scenario: backend \"sim\" needs a scenario file (scenario = "
                "\"scenarios/demo.toml\")"},
        BadCase{"CanWithoutBackend", std::string(kCan) + kWheels + kWheelSensor,
                "hw.toml:2:1: hardware.backend: [can] needs hardware.backend = \"linux\" (real devices) or \"sim\""},
        BadCase{"NodeIdOutOfRange",
                kLinux + "[can]\n[[can.node]]\nnode_id = 128\nside = \"left\"\n[[can.node]]\nnode_id = 2\nside = "
                         "\"right\"\n",
                "hw.toml:5:11: can.node[0].node_id: must be between 1 and 127, got 128"},
        BadCase{"DuplicateNode",
                kLinux + "[can]\n[[can.node]]\nnode_id = 3\nside = \"left\"\n[[can.node]]\nnode_id = 3\nside = "
                         "\"right\"\n",
                "hw.toml:8:11: can.node[1].node_id: node 3 is also can.node[0]"},
        BadCase{"OneSideOnly", kLinux + "[can]\n[[can.node]]\nnode_id = 3\nside = \"left\"\n",
                "hw.toml:3:1: can.node: needs at least one [[can.node]] with side = \"left\" and one with side = "
                "\"right\""},
        BadCase{"PositionDoesNotFit",
                kLinux + "[can]\n[[can.node]]\nnode_id = 1\nside = \"left\"\nposition_offset = 6\n[[can.node]]\n"
                         "node_id = 2\nside = \"right\"\n",
                "hw.toml:7:19: can.node[0].position_offset: position_offset + position_bits/8 must fit the 8 "
                "data bytes of a CAN frame, got 6 + 4"},
        BadCase{"BadBits",
                kLinux + "[can]\n[[can.node]]\nnode_id = 1\nside = \"left\"\nposition_bits = 12\n[[can.node]]\n"
                         "node_id = 2\nside = \"right\"\n",
                "hw.toml:7:17: can.node[0].position_bits: must be 8, 16, 24 or 32, got 12"},
        BadCase{"VoWithoutCamera", kLinux + "[vo]\nmin_inliers = 30\n" + kStereoSensor,
                "hw.toml:3:1: vo: needs a [camera] section: the odometry runs on its frames"},
        BadCase{"StereoSourceWithoutVo", kLinux + kCamera + kStereoSensor,
                "hw.toml:6:1: sensor[0].source: source 'stereo_vo' needs a [vo] section"},
        BadCase{"VoThresholdOutOfRange", kLinux + kCamera + "[vo]\ninlier_threshold = 50\n" + kStereoSensor,
                "hw.toml:6:20: vo.inlier_threshold: must be > 0 and <= 20 px, got 50"},
        BadCase{"VoUnknownKey", kLinux + kCamera + "[vo]\nransac = 100\n" + kStereoSensor,
                "hw.toml:6:1: vo.ransac: unknown key"},
        BadCase{"VoNotFused", kLinux + kCamera + "[vo]\n",
                "hw.toml:5:1: vo: no [[sensor]] with source = 'stereo_vo' fuses it"},
        BadCase{"StereoSourceAsPose",
                kLinux + kCamera + "[vo]\n[[sensor]]\nname = \"s\"\ntype = \"pose\"\nsource = \"stereo_vo\"\n"
                                   "config = [true, true, false, false, false, true, false, false, false, false, "
                                   "false, false, false, false, false]\n",
                "hw.toml:6:1: sensor[0].type: source 'stereo_vo' produces type 'twist'"},
        BadCase{"WheelSourceWithoutSection", kLinux + kCan + kWheelSensor,
                "hw.toml:18:1: sensor[0].source: source 'wheel_odometry' needs a [wheel_odometry] section"},
        BadCase{"WheelsNotFused", kLinux + kCan + kWheels,
                "hw.toml:18:1: wheel_odometry: no [[sensor]] with source = 'wheel_odometry' fuses it"},
        BadCase{"WheelSensorWrongType",
                kLinux + kCan + kWheels +
                    "[[sensor]]\nname = \"w\"\ntype = \"odometry\"\nsource = \"wheel_odometry\"\nconfig = [false, "
                    "false, false, false, false, false, true, false, false, false, false, false, false, false, "
                    "false]\n",
                "hw.toml:25:1: sensor[0].type: source 'wheel_odometry' produces type 'twist'"},
        BadCase{"ChannelWithDriverSource",
                kLinux + kCan + kWheels +
                    "[[sensor]]\nname = \"w\"\ntype = \"twist\"\nsource = \"wheel_odometry\"\nchannel = \"x\"\n"
                    "config = [false, false, false, false, false, false, true, false, false, false, false, false, "
                    "false, false, false]\n",
                "hw.toml:29:1: sensor[0].channel: not used with source = 'wheel_odometry' (the driver feeds "
                "this sensor)"},
        BadCase{"GyroRange", kLinux + "[mpu]\ngyro_range = 300\n" + kMpuSensor,
                "hw.toml:4:14: mpu.gyro_range: must be 250, 500, 1000 or 2000 deg/s, got 300"},
        BadCase{"DataReadyHalf", kLinux + "[mpu]\ndata_ready_line = 3\n" + kMpuSensor,
                "hw.toml:4:1: mpu.data_ready_line: data_ready_chip and data_ready_line go together: give both, "
                "or neither to poll at poll_rate"},
        BadCase{"MahonyGainOnMadgwick", kLinux + "[mpu]\n[mpu.attitude]\nkp = 3\n" + kMpuSensor,
                "hw.toml:5:1: mpu.attitude.kp: only used with algorithm = \"mahony\""},
        BadCase{"UnknownMpuModel", kLinux + "[mpu]\nmodel = \"bmi088\"\n" + kMpuSensor,
                "hw.toml:4:9: mpu.model: must be one of auto, mpu6050, mpu6500, mpu9250, got 'bmi088'"}),
    [](const ::testing::TestParamInfo<BadCase>& i) { return std::string(i.param.name); });

}  // namespace hardware_config_test
}  // namespace rtfuse
