// The simulated robot's IMU side: data-ready edges at the rate, registers
// holding gravity plus the true motion through the mounting, noise with the
// asked statistics, and the same values whoever asks when.
#include "sim/sim_imu.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "drivers/imu/stillness_bias.hpp"
#include "geometry/rotation.hpp"
#include "hal/mock/sim_clock.hpp"
#include "sim/truth_trajectory.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::sim {
namespace sim_imu_test {

using hal::GpioEdge;
using hal::HalStatus;
using hal::mock::SimClock;
namespace mpu = sim::mpu;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSec = 1'000 * kMs;
constexpr TimeNs kT0 = 700 * kSec;
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kG = 9.80665;

// A steady left turn: 1 m/s on a 2 m radius, after a straight run-up.
DriveScenario turning_drive() {
  DriveScenario sc;
  PathSegment a;
  a.type = SegmentType::kStraight;
  a.length_m = 2.0;
  a.speed_mps = 1.0;
  PathSegment b;
  b.type = SegmentType::kArc;
  b.radius_m = 2.0;
  b.angle_rad = 3.0 * kPi;
  b.speed_mps = 1.0;
  sc.path = {a, b};
  sc.robot.wheel_count = 2;
  sc.robot.wheels[0] = SimWheel{1, true, 0.0};
  sc.robot.wheels[1] = SimWheel{2, false, 0.0};
  sc.imu.rate_hz = 200.0;
  sc.imu.gyro_noise_density = 0.0;
  sc.imu.accel_noise_density = 0.0;
  return sc;
}

// What the IMU driver does at start-up, enough for samples and edges.
void configure(SimImu& imu, std::uint8_t addr = 0x68) {
  ASSERT_EQ(imu.write_register(addr, mpu::kPwrMgmt1, 0x01), HalStatus::kOk);  // awake, gyro PLL
  ASSERT_EQ(imu.write_register(addr, mpu::kSmplrtDiv, 4), HalStatus::kOk);   // 1 kHz / 5
  ASSERT_EQ(imu.write_register(addr, mpu::kConfig, 3), HalStatus::kOk);      // DLPF on
  ASSERT_EQ(imu.write_register(addr, mpu::kGyroConfig, 1 << 3), HalStatus::kOk);   // 500 deg/s
  ASSERT_EQ(imu.write_register(addr, mpu::kAccelConfig, 1 << 3), HalStatus::kOk);  // 4 g
  ASSERT_EQ(imu.write_register(addr, mpu::kIntPinCfg, mpu::kIntRdClear), HalStatus::kOk);
  ASSERT_EQ(imu.write_register(addr, mpu::kIntEnable, mpu::kDataRdyEn), HalStatus::kOk);
}

struct Decoded {
  double accel[3];
  double gyro[3];
  double temp;
  std::uint8_t bytes[14];
};

Decoded burst_read(SimImu& imu, sim::MpuChip model = sim::MpuChip::kMpu6050) {
  Decoded d{};
  EXPECT_EQ(imu.read_registers(0x68, mpu::kAccelXoutH, d.bytes, 14), HalStatus::kOk);
  auto be16 = [&](int i) { return static_cast<std::int16_t>((d.bytes[i] << 8) | d.bytes[i + 1]); };
  const double a_scale = kG / mpu::accel_lsb_per_g(1);
  const double g_scale = kDeg / mpu::gyro_lsb_per_dps(1);
  for (int i = 0; i < 3; ++i) {
    d.accel[i] = be16(2 * i) * a_scale;
    d.gyro[i] = be16(8 + 2 * i) * g_scale;
  }
  d.temp = mpu::temperature_c(model, be16(6));
  return d;
}

TEST(SimImu, EdgesComeAtTheRateAndTheWaitMovesTheClock) {
  const DriveScenario sc = turning_drive();
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  configure(imu);
  EXPECT_EQ(imu.next_edge_time(), kT0);
  GpioEdge e;
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(imu.wait_edge(kSec, &e), HalStatus::kOk);
    EXPECT_EQ(e.stamp, kT0 + k * 5 * kMs);
    EXPECT_TRUE(e.rising);
    EXPECT_EQ(clock.now(), e.stamp);  // it slept until the edge
  }
  EXPECT_EQ(imu.next_edge_time(), kT0 + 250 * kMs);
  // Next edge 5 ms away, 2 ms timeout: sleeps the 2 ms and times out.
  ASSERT_EQ(imu.wait_edge(2 * kMs, &e), HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), kT0 + 247 * kMs);
  ASSERT_EQ(imu.wait_edge(0, &e), HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), kT0 + 247 * kMs);
  ASSERT_EQ(imu.wait_edge(3 * kMs, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, kT0 + 250 * kMs);
  EXPECT_EQ(imu.edges(), 51);
  EXPECT_EQ(imu.config_mismatch(), nullptr);
}

TEST(SimImu, ASleepingChipOrOneWithoutDataReadyRaisesNoEdge) {
  const DriveScenario sc = turning_drive();
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  GpioEdge e;
  // The MPU-6050 powers up asleep.
  EXPECT_EQ(imu.wait_edge(100 * kMs, &e), HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), kT0 + 100 * kMs);
  EXPECT_NE(imu.config_mismatch(), nullptr);  // reset values: 8 kHz, 250 deg/s, 2 g
  // Awake but DATA_RDY_EN off: samples latch, no edge.
  ASSERT_EQ(imu.write_register(0x68, mpu::kPwrMgmt1, 0x01), HalStatus::kOk);
  EXPECT_EQ(imu.wait_edge(20 * kMs, &e), HalStatus::kTimeout);
  EXPECT_NE(imu.chip().peek16(mpu::kAccelXoutH + 4), 0);  // gravity on z
  EXPECT_EQ(imu.edges(), 0);
}

TEST(SimImu, RegistersHoldGravityAndTheTrueMotionThroughTheMounting) {
  DriveScenario sc = turning_drive();
  sc.imu.xyz_m = {0.3, -0.2, 0.1};
  sc.imu.rpy_rad = {kPi, 0.0, 0.5 * kPi};  // upside down, turned left
  sc.imu.temperature_c = 41.0;
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  configure(imu);
  const Eigen::Matrix3d r = geometry::rotation_from_rpy(kPi, 0.0, 0.5 * kPi);
  GpioEdge e;
  int checked = 0;
  bool saw_tangential = false;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(imu.wait_edge(kSec, &e), HalStatus::kOk);
    const Decoded d = burst_read(imu);
    const TruthState s = truth.truth_at(ns_to_sec(e.stamp - kT0));
    // Specific force at the IMU, base_link axes: the base's acceleration,
    // the lever arm's tangential and centripetal parts, minus gravity.
    const double w = s.yaw_rate, dw = s.yaw_accel;
    const Eigen::Vector3d f(s.accel_body[0] - dw * -0.2 - w * w * 0.3, s.accel_body[1] + dw * 0.3 - w * w * -0.2, kG);
    const Eigen::Vector3d f_imu = r.transpose() * f;
    const Eigen::Vector3d w_imu = r.transpose() * Eigen::Vector3d(0.0, 0.0, w);
    for (int i = 0; i < 3; ++i) {
      ASSERT_NEAR(d.accel[i], f_imu[i], 0.6 * kG / 8192.0) << k << " axis " << i;  // within the LSB
      ASSERT_NEAR(d.gyro[i], w_imu[i], 0.6 * kDeg / 65.5) << k << " axis " << i;
    }
    ASSERT_NEAR(d.temp, 41.0, 0.01);
    saw_tangential = saw_tangential || std::abs(dw) > 0.1;
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
  EXPECT_TRUE(saw_tangential);  // the clothoid into the arc was in there
  // On the arc: upside down, z reads -g; the 0.5 rad/s left turn reads on
  // the IMU's -z; the centripetal 0.5 m/s^2 (base +y) reads on IMU +x.
  const TruthState s = truth.truth_at(ns_to_sec(e.stamp - kT0));
  ASSERT_NEAR(s.yaw_rate, 0.5, 1e-9);
  const Decoded d = burst_read(imu);
  EXPECT_NEAR(d.accel[2], -kG, 0.002);
  EXPECT_NEAR(d.gyro[2], -0.5, 0.001);
  EXPECT_NEAR(d.accel[0], 0.5 - 0.25 * -0.2, 0.002);
}

TEST(SimImu, NoiseHasTheDensityTimesRootHalfTheRateAndTheBiasAsMean) {
  DriveScenario sc = turning_drive();
  sc.path.clear();  // standing still
  sc.duration_s = 1000.0;
  sc.imu.gyro_noise_density = 0.005 * kDeg;    // MPU-6050
  sc.imu.accel_noise_density = 400e-6 * kG;
  sc.imu.gyro_bias_rad_s = {0.01, -0.02, 0.005};
  sc.imu.accel_bias_mps2 = {0.1, 0.0, -0.05};
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  configure(imu);
  const double gyro_sigma = 0.005 * kDeg * std::sqrt(100.0);
  const double accel_sigma = 400e-6 * kG * std::sqrt(100.0);
  EXPECT_DOUBLE_EQ(imu.gyro_noise_sigma(), gyro_sigma);
  EXPECT_DOUBLE_EQ(imu.accel_noise_sigma(), accel_sigma);
  constexpr int kN = 40'000;
  double gs[3] = {}, gss[3] = {}, as[3] = {}, ass[3] = {};
  GpioEdge e;
  for (int k = 0; k < kN; ++k) {
    ASSERT_EQ(imu.wait_edge(kSec, &e), HalStatus::kOk);
    const Decoded d = burst_read(imu);
    for (int i = 0; i < 3; ++i) {
      gs[i] += d.gyro[i];
      gss[i] += d.gyro[i] * d.gyro[i];
      as[i] += d.accel[i];
      ass[i] += d.accel[i] * d.accel[i];
    }
  }
  const double gyro_bias[3] = {0.01, -0.02, 0.005};
  const double accel_mean[3] = {0.1, 0.0, kG - 0.05};
  for (int i = 0; i < 3; ++i) {
    const double gm = gs[i] / kN, am = as[i] / kN;
    const double gsd = std::sqrt(gss[i] / kN - gm * gm), asd = std::sqrt(ass[i] / kN - am * am);
    // Means within 4 standard errors (plus half an LSB of rounding bias);
    // spreads within 3 % (the register LSB adds 0.7 % to the gyro's).
    EXPECT_NEAR(gm, gyro_bias[i], 4.0 * gyro_sigma / std::sqrt(kN) + 0.5 * kDeg / 65.5) << i;
    EXPECT_NEAR(am, accel_mean[i], 4.0 * accel_sigma / std::sqrt(kN) + 0.5 * kG / 8192.0) << i;
    EXPECT_NEAR(gsd, gyro_sigma, 0.03 * gyro_sigma) << i;
    EXPECT_NEAR(asd, accel_sigma, 0.03 * accel_sigma) << i;
  }
}

// Bytes of every edge, keyed by stamp.
struct Recorded {
  TimeNs stamp;
  std::uint8_t bytes[14];
};

TEST(SimImu, SameSeedSameBytesWhateverTheCallPattern) {
  DriveScenario sc = turning_drive();
  sc.seed = 1234;
  sc.imu.gyro_noise_density = 0.005 * kDeg;
  sc.imu.accel_noise_density = 400e-6 * kG;
  TruthTrajectory truth_a(sc);
  TruthTrajectory truth_b(sc);
  SimClock clock_a(kT0), clock_b(kT0);
  SimImu a(sc, truth_a, clock_a, kT0);
  SimImu b(sc, truth_b, clock_b, kT0);
  configure(a);
  configure(b);
  GpioEdge e;
  // A reads every edge as it comes.
  std::vector<Recorded> ra;
  for (int k = 0; k < 600; ++k) {
    ASSERT_EQ(a.wait_edge(kSec, &e), HalStatus::kOk);
    Recorded r{e.stamp, {}};
    ASSERT_EQ(a.read_registers(0x68, mpu::kAccelXoutH, r.bytes, 14), HalStatus::kOk);
    ra.push_back(r);
  }
  // B times out now and then, reads other registers in between and falls a
  // second behind once (the kernel queue keeps the last 16 edges).
  std::vector<Recorded> rb;
  for (int k = 0; k < 400; ++k) {
    if (k % 7 == 0 && b.next_edge_time() > clock_b.now()) {
      EXPECT_EQ(b.wait_edge(0, &e), HalStatus::kTimeout);
    }
    if (k == 100) clock_b.set(clock_b.now() + kSec);
    std::uint8_t junk[2];
    ASSERT_EQ(b.read_registers(0x68, mpu::kIntStatus, junk, 1), HalStatus::kOk);
    ASSERT_EQ(b.wait_edge(kSec, &e), HalStatus::kOk);
    Recorded r{e.stamp, {}};
    ASSERT_EQ(b.read_registers(0x68, mpu::kAccelXoutH, r.bytes, 14), HalStatus::kOk);
    rb.push_back(r);
  }
  EXPECT_GT(b.samples_skipped(), 150);
  int compared = 0;
  for (const Recorded& r : rb) {
    const TimeNs k = (r.stamp - kT0) / (5 * kMs);
    if (k >= static_cast<TimeNs>(ra.size())) continue;
    ASSERT_EQ(ra[static_cast<std::size_t>(k)].stamp, r.stamp);
    ASSERT_EQ(std::memcmp(ra[static_cast<std::size_t>(k)].bytes, r.bytes, 14), 0) << "sample " << k;
    ++compared;
  }
  EXPECT_GT(compared, 250);
  // Another seed, other noise.
  sc.seed = 1235;
  SimClock clock_c(kT0);
  SimImu c(sc, truth_a, clock_c, kT0);
  EXPECT_NE(c.sample(10).gyro_rad_s[0], a.sample(10).gyro_rad_s[0]);
  EXPECT_EQ(b.sample(10).gyro_rad_s[0], a.sample(10).gyro_rad_s[0]);
}

TEST(SimImu, WaitAndBurstReadDoNotAllocate) {
  DriveScenario sc = turning_drive();
  sc.imu.gyro_noise_density = 0.005 * kDeg;
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  configure(imu);
  GpioEdge e;
  std::uint8_t buf[14];
  int ok = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int k = 0; k < 1000; ++k) {
      ok += imu.wait_edge(kSec, &e) == HalStatus::kOk;
      ok += imu.read_registers(0x68, mpu::kAccelXoutH, buf, 14) == HalStatus::kOk;
      if (k % 10 == 0) imu.wait_edge(kMs, &e);
    }
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_GE(ok, 2000);
}

TEST(SimImu, ModelAndAddressComeFromTheScenario) {
  DriveScenario sc = turning_drive();
  sc.imu.model = MpuChip::kMpu9250;
  sc.imu.address = 0x69;
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimImu imu(sc, truth, clock, kT0);
  std::uint8_t who = 0;
  EXPECT_EQ(imu.read_registers(0x68, mpu::kWhoAmI, &who, 1), HalStatus::kNack);
  ASSERT_EQ(imu.read_registers(0x69, mpu::kWhoAmI, &who, 1), HalStatus::kOk);
  EXPECT_EQ(who, 0x71);
}

// Standing 10 s, then straight ahead at `speed` for a minute; the chip
// itself noise-free, so what is left after the truth is the vibration.
DriveScenario rolling_drive(double speed, double vibration_accel, double vibration_gyro) {
  DriveScenario sc = turning_drive();
  PathSegment stop;
  stop.type = SegmentType::kStop;
  stop.duration_s = 10.0;
  PathSegment ahead;
  ahead.type = SegmentType::kStraight;
  ahead.length_m = 60.0 * speed;
  ahead.speed_mps = speed;
  sc.path = {stop, ahead};
  sc.duration_s = 80.0;
  sc.imu.vibration_accel_mps2 = vibration_accel;
  sc.imu.vibration_gyro_rad_s = vibration_gyro;
  sc.imu.vibration_speed_mps = 0.3;
  return sc;
}

// Spread of sample - ideal over samples [k0, k1), per axis: {gyro, accel}.
std::pair<double, double> vibration_spread(const SimImu& imu, std::int64_t k0, std::int64_t k1, int axis) {
  double gss = 0.0, ass = 0.0;
  for (std::int64_t k = k0; k < k1; ++k) {
    const ImuChipReading s = imu.sample(k);
    const ImuChipReading t = imu.ideal_sample(k);
    gss += (s.gyro_rad_s[axis] - t.gyro_rad_s[axis]) * (s.gyro_rad_s[axis] - t.gyro_rad_s[axis]);
    ass += (s.accel_mps2[axis] - t.accel_mps2[axis]) * (s.accel_mps2[axis] - t.accel_mps2[axis]);
  }
  const auto n = static_cast<double>(k1 - k0);
  return {std::sqrt(gss / n), std::sqrt(ass / n)};
}

TEST(SimImu, TheBaseVibratesOnlyWhileItsWheelsRollAndInProportionBelowTheFullSpeed) {
  for (const double speed : {1.0, 0.15}) {
    DriveScenario sc = rolling_drive(speed, 0.3, 1.0 * kDeg);
    TruthTrajectory truth(sc);
    SimClock clock(kT0);
    SimImu imu(sc, truth, clock, kT0);
    // Samples at 200 Hz: at rest 1-9 s, cruising 25-65 s.
    const double share = std::min(1.0, speed / 0.3);
    for (int axis = 0; axis < 3; ++axis) {
      const auto rest = vibration_spread(imu, 200, 1800, axis);
      EXPECT_EQ(rest.first, 0.0) << axis;
      EXPECT_EQ(rest.second, 0.0) << axis;
      const auto rolling = vibration_spread(imu, 5000, 13000, axis);  // 8000 samples: 1.6 % std error
      EXPECT_NEAR(rolling.first, share * 1.0 * kDeg, 0.05 * share * kDeg) << speed << " " << axis;
      EXPECT_NEAR(rolling.second, share * 0.3, 0.05 * share * 0.3) << speed << " " << axis;
    }
  }
}

// Why the simulator shakes its IMU: the driver's standstill bias learner
// tells driving from standing by the accelerometer's quiet, and a base
// that rolls without vibration (a vibration-free simulation) is as quiet as
// one standing still, so the learner would take the drive's slow turns for
// gyro bias. With a Jackal's vibration a straight drive never counts as still.
TEST(SimImu, AVibratingDriveIsNeverStillToTheDriversBiasLearner) {
  for (const bool vibrating : {false, true}) {
    DriveScenario sc = rolling_drive(0.5, vibrating ? 0.3 : 0.0, vibrating ? 1.0 * kDeg : 0.0);
    sc.imu.gyro_noise_density = 0.005 * kDeg;  // the MPU-6050's own noise
    sc.imu.accel_noise_density = 400e-6 * kG;
    TruthTrajectory truth(sc);
    SimClock clock(kT0);
    SimImu imu(sc, truth, clock, kT0);
    drivers::StillnessBiasEstimator learner;
    Eigen::Vector3d bias = Eigen::Vector3d::Zero();
    int still_at_rest = 0, still_rolling = 0;
    for (std::int64_t k = 0; k < 13000; ++k) {
      const ImuChipReading s = imu.sample(k);
      const drivers::StillnessState state =
          learner.update(Eigen::Vector3d(s.gyro_rad_s[0], s.gyro_rad_s[1], s.gyro_rad_s[2]),
                         Eigen::Vector3d(s.accel_mps2[0], s.accel_mps2[1], s.accel_mps2[2]), 0.005, &bias);
      const bool still = state == drivers::StillnessState::kStill;
      if (k < 1900) still_at_rest += still;
      if (k >= 5000) still_rolling += still;
    }
    EXPECT_GT(still_at_rest, 1500) << vibrating;  // still after its 0.5 s window
    if (vibrating) {
      EXPECT_EQ(still_rolling, 0);
    } else {
      EXPECT_GT(still_rolling, 7000);  // the vibration-free drive: "still" nearly all along
    }
  }
}

}  // namespace sim_imu_test
}  // namespace rtfuse::sim
