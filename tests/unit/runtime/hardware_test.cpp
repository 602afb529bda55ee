// Hardware: the drivers a configuration runs, on mock buses, inside the
// loop's tick (CANopen encoders + wheel odometry) and on the IMU thread's
// step (MPU): what they measure reaches the estimate, their health reaches
// the snapshot's devices, faults show and recover, and the steady state
// allocates nothing.
#include "runtime/devices/hardware.hpp"
#include "runtime/devices/imu/imu_device.hpp"

#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "sim/devices/canopen_encoder_node.hpp"
#include "hal/mock/mock_can_bus.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "core/physical_constants.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/scripted_gpio.hpp"
#include "hal/mock/sim_clock.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "support/alloc_counter.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse {
namespace hardware_test {

using sim::CanopenEncoderConfig;
using sim::CanopenEncoderNode;
using hal::mock::MockCanBus;
using hal::mock::MockCanBusCapacity;
using hal::mock::MockI2cBus;
using sim::MpuRegisterFile;
using hal::mock::ScriptedEdgeSource;
using hal::mock::SimClock;

constexpr TimeNs kT0 = 1'000'000'000;
constexpr TimeNs kPeriod = 5'000'000;  // 200 Hz, the loop and the IMU
constexpr double kPi = 3.14159265358979323846;
// wheel_odometry below: 4096 counts per turn of a 0.1 m wheel.
constexpr double kCountsPerM = 4096.0 / (2.0 * kPi * 0.1);
constexpr double kTrack = 0.5;
constexpr double kLeftMps = 0.8;
constexpr double kRightMps = 1.2;
constexpr double kVx = 0.5 * (kLeftMps + kRightMps);      // 1.0 m/s
constexpr double kVyaw = (kRightMps - kLeftMps) / kTrack;  // 0.8 rad/s

constexpr const char* kFilter = R"(
[filter]
frequency = 200
sensor_timeout = 0.1
two_d_mode = true
world_frame = "odom"

[hardware]
backend = "sim"
scenario = "not-read-by-hardware.toml"
)";

constexpr const char* kCanWheels = R"(
[can]
interface = "can0"
heartbeat_timeout = 0.35
stuck_time = 1.0
max_wheel_speed = 3.0

[[can.node]]
node_id = 1
side = "left"

[[can.node]]
node_id = 2
side = "right"

[wheel_odometry]
kinematics = "differential"
track_width = 0.5
wheel_radius = 0.1
counts_per_rev = 4096

[[sensor]]
name = "wheels"
type = "twist"
source = "wheel_odometry"
config = [false, false, false, false, false, false,
          true,  true,  false, false, false, true,
          false, false, false]
queue_size = 10
)";

constexpr const char* kMpu = R"(
[mpu]
address = 0x68
model = "mpu6050"
sample_rate_divider = 4
dlpf = 3
gyro_range = 500
accel_range = 4
data_ready_chip = "sim"
data_ready_line = 0
frame = "imu_link"

[[sensor]]
name = "imu"
type = "imu"
source = "mpu"
config = [false, false, false, false, false, false,
          false, false, false, false, false, true,
          false, false, false]
queue_size = 20
)";

constexpr const char* kImuMount = R"(
[[static_transform]]
parent = "base_link"
child = "imu_link"
translation = [0.12, -0.03, 0.08]
rpy = [0.0, 0.0, 0.0]
)";

RuntimeConfig load(const std::string& text) {
  ConfigLoadResult r = load_config_string(text, "hardware_test.toml");
  for (const ConfigError& e : r.errors) ADD_FAILURE() << e.to_string();
  if (!r.config) return RuntimeConfig{};
  return *r.config;
}

std::int64_t value(const DeviceStatus& d, const char* key) {
  for (int i = 0; i < d.num_values; ++i) {
    if (std::strcmp(d.keys[i], key) == 0) return d.values[i];
  }
  ADD_FAILURE() << "device '" << d.name.c_str() << "' has no counter '" << key << "'";
  return -1;
}

bool all_finite(const Snapshot& s) {
  for (double v : s.state) {
    if (!std::isfinite(v)) return false;
  }
  for (double v : s.covariance) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

CanopenEncoderConfig node_config(std::uint8_t id, double mps) {
  CanopenEncoderConfig c;
  c.node_id = id;
  c.heartbeat_period_ns = 100'000'000;
  c.position_width = 4;
  c.speed_counts_per_s = mps * kCountsPerM;
  return c;
}

// Two wheel encoders on a mock CAN bus driven by a simulated clock, the
// loop's tick at 200 Hz.
struct CanRig {
  explicit CanRig(const std::string& extra = "")
      : bus(MockCanBusCapacity{}, &clock),
        left(node_config(1, kLeftMps)),
        right(node_config(2, kRightMps)) {
    std::string err;
    core = FusionCore::create(load(std::string(kFilter) + kCanWheels + extra), &err);
    EXPECT_TRUE(core) << err;
    if (!core) return;
    EXPECT_TRUE(bus.attach(left));
    EXPECT_TRUE(bus.attach(right));
    HalBuses buses;
    buses.of("wheel_encoders").can = &bus;
    hardware = Hardware::create(buses, *core, &err);
    EXPECT_TRUE(hardware) << err;
    if (!hardware) return;
    core->set_devices(hardware.get());
    EXPECT_TRUE(hardware->start(kT0, &err)) << err;
    loop.rate_hz = 200;
    loop.period_ns = kPeriod;
  }
  bool ready() const { return core && hardware; }
  void tick() {
    clock.set(t);
    ++loop.ticks;
    core->tick(t, loop);
    t += kPeriod;
  }
  void run(int ticks) {
    for (int i = 0; i < ticks; ++i) tick();
  }
  const Snapshot& snap() {
    core->snapshot().load(s);
    return s;
  }

  SimClock clock{kT0};
  MockCanBus bus;
  CanopenEncoderNode left, right;
  std::unique_ptr<FusionCore> core;
  std::unique_ptr<Hardware> hardware;
  LoopStats loop;
  TimeNs t = kT0;
  Snapshot s;
};

TEST(Hardware, WheelEncodersGiveTheEstimateTheirTwist) {
  CanRig rig;
  ASSERT_TRUE(rig.ready());
  rig.run(600);  // 3 s
  const Snapshot& s = rig.snap();
  ASSERT_TRUE(s.initialized);
  EXPECT_TRUE(all_finite(s));
  EXPECT_NEAR(s.state[6], kVx, 0.01) << "vx";
  EXPECT_NEAR(s.state[7], 0.0, 0.01) << "vy";
  EXPECT_NEAR(s.state[11], kVyaw, 0.02) << "vyaw";
  // 3 s of a 0.8 rad/s turn at 1 m/s: on the circle of radius 1.25 m.
  EXPECT_NEAR(std::hypot(s.state[0], s.state[1] - 1.25), 1.25, 0.05);
  // The raw wheel odometry says the same.
  ASSERT_TRUE(s.wheel_odometry.valid);
  EXPECT_NEAR(s.wheel_odometry.vx, kVx, 0.04);
  EXPECT_NEAR(s.wheel_odometry.vyaw, kVyaw, 0.2);
  EXPECT_NEAR(s.wheel_odometry.yaw, std::remainder(kVyaw * (599 - 1) * 0.005, 2 * kPi), 0.02);
  // One twist per SYNC once the second set closed, every one fused.
  EXPECT_EQ(s.sensors[0].accepted, s.sensors[0].received);
  EXPECT_GE(s.sensors[0].accepted, 595);
  EXPECT_EQ(s.sensors[0].rejected_mahalanobis, 0);
}

TEST(Hardware, DeviceStatusNamesLevelsAndCounters) {
  CanRig rig;
  ASSERT_TRUE(rig.ready());
  constexpr int kTicks = 400;
  rig.run(kTicks);
  const Snapshot& s = rig.snap();
  ASSERT_EQ(s.num_devices, 4);
  EXPECT_STREQ(s.devices[0].name.c_str(), "can bus");
  EXPECT_STREQ(s.devices[0].hardware_id.c_str(), "can0");
  EXPECT_STREQ(s.devices[1].name.c_str(), "wheel left node 1");
  EXPECT_STREQ(s.devices[1].hardware_id.c_str(), "can0 node 0x01");
  EXPECT_STREQ(s.devices[2].name.c_str(), "wheel right node 2");
  EXPECT_STREQ(s.devices[2].hardware_id.c_str(), "can0 node 0x02");
  EXPECT_STREQ(s.devices[3].name.c_str(), "wheel odometry");
  for (int i = 0; i < 4; ++i) EXPECT_EQ(s.devices[i].level, DeviceLevel::kOk) << s.devices[i].name.c_str();
  EXPECT_STREQ(s.devices[0].state.c_str(), "error-active");
  EXPECT_STREQ(s.devices[1].state.c_str(), "ok");
  EXPECT_STREQ(s.devices[2].state.c_str(), "ok");
  EXPECT_STREQ(s.devices[3].state.c_str(), "running");
  for (int i = 0; i < 4; ++i) EXPECT_STREQ(s.devices[i].message.c_str(), "") << "no error yet";

  const DeviceStatus& bus = s.devices[0];
  // One SYNC per tick; besides them only the two NMT starts went out.
  EXPECT_EQ(value(bus, "syncs_sent"), kTicks);
  EXPECT_EQ(rig.bus.total_sent(), kTicks + 2);
  EXPECT_EQ(value(bus, "send_failures"), 0);
  EXPECT_EQ(value(bus, "malformed_frames"), 0);
  EXPECT_EQ(value(bus, "unexpected_cob_ids"), 0);
  EXPECT_EQ(value(bus, "bus_off_events"), 0);
  std::int64_t node_frames = 0;
  for (int n = 1; n <= 2; ++n) {
    const DeviceStatus& d = s.devices[n];
    // The TPDO answering the last SYNC is still queued.
    EXPECT_EQ(value(d, "tpdos"), kTicks - 1) << d.name.c_str();
    // Boot-up at t0, then one every 100 ms up to the last poll at 1.995 s.
    EXPECT_EQ(value(d, "heartbeats"), 1 + 19) << d.name.c_str();
    EXPECT_EQ(value(d, "silent_events"), 0);
    EXPECT_EQ(value(d, "recoveries"), 0);
    EXPECT_EQ(value(d, "nmt_starts"), 1);
    node_frames += value(d, "tpdos") + value(d, "heartbeats");
  }
  EXPECT_EQ(value(bus, "frames_received"), node_frames);
  // Counts are the node's position at the last attributed SYNC (1.99 s).
  EXPECT_NEAR(static_cast<double>(value(s.devices[1], "counts")), kLeftMps * kCountsPerM * 1.99, 1.0);
  EXPECT_NEAR(static_cast<double>(value(s.devices[2], "counts")), kRightMps * kCountsPerM * 1.99, 1.0);
  // First set seeds, every later one gives a twist.
  EXPECT_EQ(value(s.devices[3], "twists"), kTicks - 2);
  EXPECT_EQ(value(s.devices[3], "reseeds"), 1);
  EXPECT_EQ(value(s.devices[3], "no_side"), 0);
}

TEST(Hardware, SilentNodeIsReportedAndRecovers) {
  CanRig rig;
  ASSERT_TRUE(rig.ready());
  rig.run(200);
  const std::int64_t accepted_before = rig.snap().sensors[0].accepted;
  rig.right.set_silent(true, rig.t);
  rig.run(40);  // 0.2 s: beyond tpdo_timeout_syncs and the sensor timeout
  const std::int64_t accepted_silent = rig.snap().sensors[0].accepted;
  EXPECT_LE(accepted_silent - accepted_before, 2);
  rig.run(360);  // 2 s silent in all
  {
    const Snapshot& s = rig.snap();
    const DeviceStatus& right = s.devices[2];
    EXPECT_EQ(right.level, DeviceLevel::kError);
    EXPECT_STREQ(right.state.c_str(), "silent");
    EXPECT_STREQ(right.message.c_str(), "node 2: no TPDO for 5 SYNCs in a row");
    EXPECT_EQ(value(right, "silent_events"), 1);
    EXPECT_EQ(s.devices[1].level, DeviceLevel::kOk) << "the left node kept answering";
    EXPECT_STREQ(s.devices[1].message.c_str(), "");
    // Without its right side the wheels give no twist: nothing fused, the
    // sensor timed out, the estimate coasts but stays finite.
    EXPECT_EQ(s.sensors[0].accepted, accepted_silent);
    EXPECT_TRUE(s.sensors[0].timed_out);
    EXPECT_GE(value(s.devices[3], "no_side"), 390);
    EXPECT_TRUE(all_finite(s));
    EXPECT_NEAR(s.state[6], kVx, 0.2);
  }
  rig.right.set_silent(false, rig.t);
  rig.run(200);
  const Snapshot& s = rig.snap();
  const DeviceStatus& right = s.devices[2];
  EXPECT_EQ(right.level, DeviceLevel::kOk);
  EXPECT_STREQ(right.state.c_str(), "ok");
  EXPECT_STREQ(right.message.c_str(), "node 2: no TPDO for 5 SYNCs in a row") << "the last error is kept";
  EXPECT_EQ(value(right, "recoveries"), 1);
  EXPECT_EQ(value(right, "silent_events"), 1);
  EXPECT_GT(s.sensors[0].accepted, accepted_silent + 150);
  EXPECT_FALSE(s.sensors[0].timed_out);
  EXPECT_NEAR(s.state[6], kVx, 0.02);
  EXPECT_NEAR(s.state[11], kVyaw, 0.05);
}

TEST(Hardware, BusOffIsAnErrorOfTheBusAndRecovers) {
  CanRig rig;
  ASSERT_TRUE(rig.ready());
  rig.run(200);
  rig.bus.set_state(hal::CanBusState::kBusOff);
  rig.run(100);
  {
    const Snapshot& s = rig.snap();
    const DeviceStatus& bus = s.devices[0];
    EXPECT_EQ(bus.level, DeviceLevel::kError);
    EXPECT_STREQ(bus.state.c_str(), "bus-off");
    EXPECT_EQ(value(bus, "bus_off_events"), 1);
    // Every SYNC of the 100 ticks was refused.
    EXPECT_EQ(value(bus, "send_failures"), 100);
    EXPECT_EQ(value(bus, "syncs_sent"), 200);
    // The refused SYNCs came after the bus-off itself.
    EXPECT_STREQ(bus.message.c_str(), "SYNC (COB-ID 0x080) refused by the bus: mock: bus-off");
    for (int n = 1; n <= 2; ++n) {
      EXPECT_EQ(s.devices[n].level, DeviceLevel::kError);
      EXPECT_STREQ(s.devices[n].state.c_str(), "bus-off");
      EXPECT_STREQ(s.devices[n].message.c_str(), "") << "bus-off is the bus's error";
    }
    EXPECT_TRUE(all_finite(s));
  }
  rig.bus.set_state(hal::CanBusState::kErrorActive);
  rig.run(100);
  const Snapshot& s = rig.snap();
  const DeviceStatus& bus = s.devices[0];
  EXPECT_EQ(bus.level, DeviceLevel::kOk);
  EXPECT_STREQ(bus.state.c_str(), "error-active");
  EXPECT_EQ(value(bus, "bus_off_events"), 1);
  EXPECT_EQ(value(bus, "syncs_sent"), 300);
  for (int n = 1; n <= 2; ++n) {
    EXPECT_EQ(s.devices[n].level, DeviceLevel::kOk) << s.devices[n].name.c_str();
    EXPECT_STREQ(s.devices[n].state.c_str(), "ok");
    EXPECT_EQ(value(s.devices[n], "recoveries"), 1);
    EXPECT_EQ(value(s.devices[n], "silent_events"), 0) << "bus-off is not silence";
  }
  EXPECT_NEAR(s.state[6], kVx, 0.02);
}

TEST(Hardware, SteadyStateTicksAllocateNothing) {
  CanRig rig;
  ASSERT_TRUE(rig.ready());
  rig.run(400);
  const std::int64_t accepted = rig.snap().sensors[0].accepted;
  std::size_t allocations = 0;
  {
    test::EigenMallocForbidden eigen_no_malloc;
    test::AllocScope scope;
    rig.run(2000);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  // The work was done: 2000 twists fused, 2000 SYNCs sent.
  const Snapshot& s = rig.snap();
  EXPECT_EQ(s.sensors[0].accepted - accepted, 2000);
  EXPECT_EQ(value(s.devices[0], "syncs_sent"), 2400);
}

// An MPU-6050 on a mock I2C bus with a scripted data-ready line; the IMU
// thread's steps are interleaved with the loop's ticks.
struct ImuRig {
  explicit ImuRig(const std::string& text) : chip(sim::MpuChip::kMpu6050), edges(256, &clock) {
    EXPECT_TRUE(i2c.attach(0x68, chip));
    std::string err;
    core = FusionCore::create(load(text), &err);
    EXPECT_TRUE(core) << err;
  }
  bool start() {
    HalBuses buses;
    buses.of("imu").i2c = &i2c;
    buses.of("imu").edge = &edges;
    buses.of("imu").clock = &clock;
    hardware = Hardware::create(buses, *core, &error);
    if (!hardware) return false;
    core->set_devices(hardware.get());
    if (!hardware->start(clock.now(), &error)) return false;
    // The chip reset slept on the clock: go on from there.
    t = clock.now();
    loop.rate_hz = 200;
    loop.period_ns = kPeriod;
    return true;
  }
  // One chip sample with its data-ready edge, one IMU step, one tick.
  drivers::StepResult step(double yaw_rate) {
    t += kPeriod;
    clock.set(t);
    ++n;
    // A small varying x so consecutive samples are never identical (the
    // driver calls a chip that repeats itself frozen).
    const double accel[3] = {2e-3 * (n % 7), 0.0, kStandardGravity};
    const double gyro[3] = {0.0, 0.0, yaw_rate};
    if (!chip.set_sample(accel, gyro, 25.0)) ++chip_refused;
    edges.push(t);
    const drivers::StepResult r = hardware->find<ImuDevice>("imu")->step_imu(kDeviceStepTimeoutNs);
    clock.set(t);
    ++loop.ticks;
    core->tick(t, loop);
    return r;
  }
  const Snapshot& snap() {
    core->snapshot().load(s);
    return s;
  }

  SimClock clock{kT0};
  MockI2cBus i2c;
  MpuRegisterFile chip;
  ScriptedEdgeSource edges;
  std::unique_ptr<FusionCore> core;
  std::unique_ptr<Hardware> hardware;
  std::string error;
  LoopStats loop;
  TimeNs t = kT0;
  int n = 0;
  int chip_refused = 0;
  Snapshot s;
};

TEST(Hardware, ImuYawRateReachesTheEstimate) {
  ImuRig rig(std::string(kFilter) + kMpu + kImuMount);
  ASSERT_TRUE(rig.core);
  ASSERT_TRUE(rig.start()) << rig.error;
  ASSERT_TRUE(rig.hardware->find<ImuDevice>("imu") != nullptr);
  constexpr double kRate = 0.5;  // rad/s, above the standstill threshold
  int samples = 0;
  for (int i = 0; i < 400; ++i) samples += rig.step(kRate) == drivers::StepResult::kSample;
  EXPECT_EQ(rig.chip_refused, 0) << "data-ready was not enabled by the driver";
  EXPECT_EQ(samples, 400);
  EXPECT_EQ(rig.hardware->find<ImuDevice>("imu")->samples(), 400);
  const Snapshot& s = rig.snap();
  ASSERT_TRUE(s.initialized);
  EXPECT_TRUE(all_finite(s));
  // 500 dps range: 65.5 LSB per deg/s, so the chip quantises 0.5 rad/s to 2.7e-4 rad/s.
  EXPECT_NEAR(s.state[11], kRate, 2e-3);
  EXPECT_NEAR(s.state[6], 0.0, 1e-6) << "vx is not measured by anyone";
  EXPECT_EQ(s.sensors[0].accepted, 400);

  ASSERT_EQ(s.num_devices, 1);
  const DeviceStatus& imu = s.devices[0];
  EXPECT_STREQ(imu.name.c_str(), "imu");
  EXPECT_STREQ(imu.hardware_id.c_str(), "/dev/i2c-1 0x68");
  EXPECT_EQ(imu.level, DeviceLevel::kOk);
  EXPECT_STREQ(imu.state.c_str(), "sample");
  EXPECT_EQ(value(imu, "samples"), 400);
  EXPECT_EQ(value(imu, "nacks"), 0);
  EXPECT_EQ(value(imu, "frozen"), 0);
  EXPECT_EQ(value(imu, "missing_edges"), 0);
  EXPECT_EQ(value(imu, "reinits"), 0);
  EXPECT_NEAR(static_cast<double>(value(imu, "temperature_mdegc")), 25'000.0, 5.0);
  EXPECT_STREQ(imu.message.c_str(), "");
}

// Reads that time out until the driver initialises the chip again: the
// message says what failed and keeps saying it once samples flow again (the
// successful re-initialisation clears the driver's own text).
TEST(Hardware, ImuMessageKeepsTheLastErrorAfterRecovery) {
  ImuRig rig(std::string(kFilter) + kMpu + kImuMount);
  ASSERT_TRUE(rig.core);
  ASSERT_TRUE(rig.start()) << rig.error;
  for (int i = 0; i < 20; ++i) rig.step(0.3);
  EXPECT_STREQ(rig.snap().devices[0].message.c_str(), "");
  rig.i2c.fail_next(hal::HalStatus::kTimeout, 5);
  int samples = 0;
  for (int i = 0; i < 40; ++i) samples += rig.step(0.3) == drivers::StepResult::kSample;
  EXPECT_GT(samples, 30);
  const Snapshot& s = rig.snap();
  const DeviceStatus& imu = s.devices[0];
  EXPECT_EQ(value(imu, "reinits"), 1);
  EXPECT_STREQ(imu.state.c_str(), "sample");
  EXPECT_EQ(std::string(imu.message.c_str()).rfind("mpu at 0x68: data read failed (timeout", 0), 0u)
      << imu.message.c_str();
}

TEST(Hardware, ImuStepAllocatesNothingInSteadyState) {
  ImuRig rig(std::string(kFilter) + kMpu + kImuMount);
  ASSERT_TRUE(rig.core);
  ASSERT_TRUE(rig.start()) << rig.error;
  for (int i = 0; i < 200; ++i) rig.step(0.3);
  int samples = 0;
  std::size_t allocations = 0;
  {
    test::EigenMallocForbidden eigen_no_malloc;
    test::AllocScope scope;
    for (int i = 0; i < 1000; ++i) samples += rig.step(0.3) == drivers::StepResult::kSample;
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(samples, 1000);
  EXPECT_NEAR(rig.snap().state[11], 0.3, 2e-3);
}

TEST(Hardware, ImuFrameNotConnectedToBaseLinkIsNamed) {
  ImuRig rig(std::string(kFilter) + kMpu);  // no static transform for imu_link
  ASSERT_TRUE(rig.core);
  EXPECT_FALSE(rig.start());
  EXPECT_EQ(rig.hardware, nullptr);
  EXPECT_NE(rig.error.find("mpu.frame 'imu_link' is not connected to 'base_link'"), std::string::npos)
      << rig.error;
  EXPECT_NE(rig.error.find("[[static_transform]]"), std::string::npos) << rig.error;
}

TEST(Hardware, CanConfigWithoutACanBusIsAnError) {
  SimClock clock(kT0);
  std::string err;
  auto core = FusionCore::create(load(std::string(kFilter) + kCanWheels), &err);
  ASSERT_TRUE(core) << err;
  EXPECT_EQ(Hardware::create(HalBuses{}, *core, &err), nullptr);
  EXPECT_EQ(err, "[can] is configured but the HAL has no CAN bus");
}

}  // namespace hardware_test
}  // namespace rtfuse
