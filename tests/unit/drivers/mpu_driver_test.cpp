// MpuDriver against the mock register file: identity, configuration,
// scaling, mounting rotation, temperature.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivers/imu/mpu_driver.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/sim_clock.hpp"

namespace mpu_driver_test {

using rtfuse::drivers::ImuReading;
using rtfuse::drivers::MpuConfig;
using rtfuse::drivers::MpuDriver;
using rtfuse::drivers::MpuReadStatus;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuRegisterFile;
using rtfuse::hal::mock::SimClock;
using Chip = rtfuse::sim::MpuChip;
using Model = rtfuse::drivers::MpuModel;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr rtfuse::TimeNs kStart = 5'000'000'000;

struct Rig {
  explicit Rig(Chip chip_model = Chip::kMpu6050, MpuConfig cfg = {})
      : chip(chip_model), clock(kStart), driver(bus, clock, cfg) {
    EXPECT_TRUE(bus.attach(0x68, chip));
  }
  MpuRegisterFile chip;
  MockI2cBus bus;
  SimClock clock;
  MpuDriver driver;
};

MpuConfig with_model(Model m) {
  MpuConfig c;
  c.model = m;
  return c;
}

bool contains(const char* text, const char* part) { return std::string(text).find(part) != std::string::npos; }

struct IdentityCase {
  Chip chip;
  Model configured;
  Model expected;
};

class MpuDriverIdentity : public ::testing::TestWithParam<IdentityCase> {};

TEST_P(MpuDriverIdentity, AcceptsItsWhoAmI) {
  Rig rig(GetParam().chip, with_model(GetParam().configured));
  ASSERT_TRUE(rig.driver.init(rig.clock.now())) << rig.driver.error();
  EXPECT_EQ(rig.driver.model(), GetParam().expected);
  EXPECT_STREQ(rig.driver.error(), "");
  EXPECT_EQ(rig.driver.stats().inits, 1);
}

INSTANTIATE_TEST_SUITE_P(Models, MpuDriverIdentity,
                         ::testing::Values(IdentityCase{Chip::kMpu6050, Model::kMpu6050, Model::kMpu6050},
                                           IdentityCase{Chip::kMpu6500, Model::kMpu6500, Model::kMpu6500},
                                           IdentityCase{Chip::kMpu9250, Model::kMpu9250, Model::kMpu9250},
                                           IdentityCase{Chip::kMpu6050, Model::kAuto, Model::kMpu6050},
                                           IdentityCase{Chip::kMpu6500, Model::kAuto, Model::kMpu6500},
                                           IdentityCase{Chip::kMpu9250, Model::kAuto, Model::kMpu9250}));

TEST(MpuDriverIdentity, WrongModelNamesWhatWasReadAndExpected) {
  Rig rig(Chip::kMpu6500, with_model(Model::kMpu6050));
  EXPECT_FALSE(rig.driver.init(rig.clock.now()));
  EXPECT_FALSE(rig.driver.initialised());
  EXPECT_TRUE(contains(rig.driver.error(), "WHO_AM_I reads 0x70")) << rig.driver.error();
  EXPECT_TRUE(contains(rig.driver.error(), "expected 0x68 (MPU-6050)")) << rig.driver.error();
  EXPECT_TRUE(contains(rig.driver.error(), "set model to MPU-6500 or auto")) << rig.driver.error();
  EXPECT_EQ(rig.chip.reset_count(), 0);  // nothing was written to a chip that is not the one configured
  EXPECT_EQ(rig.driver.stats().init_failures, 1);
}

TEST(MpuDriverIdentity, UnknownPartNamesTheLikelyCause) {
  Rig lookalike(Chip::kMpu9250, with_model(Model::kMpu9250));
  lookalike.chip.set_wrong_who_am_i(0x73);
  EXPECT_FALSE(lookalike.driver.init(kStart));
  EXPECT_TRUE(contains(lookalike.driver.error(), "0x73")) << lookalike.driver.error();
  EXPECT_TRUE(contains(lookalike.driver.error(), "MPU-9255")) << lookalike.driver.error();

  Rig other(Chip::kMpu6050, with_model(Model::kAuto));
  other.chip.set_wrong_who_am_i(0x42);
  EXPECT_FALSE(other.driver.init(kStart));
  EXPECT_TRUE(contains(other.driver.error(), "WHO_AM_I reads 0x42")) << other.driver.error();
  EXPECT_TRUE(contains(other.driver.error(), "0x68, 0x70 or 0x71")) << other.driver.error();
  EXPECT_TRUE(contains(other.driver.error(), "wrong address or wrong model")) << other.driver.error();
}

TEST(MpuDriverIdentity, NoDeviceAtTheAddressPointsAtAd0) {
  MpuConfig c;
  c.address = 0x69;
  Rig rig(Chip::kMpu6050, c);  // the chip answers at 0x68
  EXPECT_FALSE(rig.driver.init(kStart));
  EXPECT_TRUE(contains(rig.driver.error(), "mpu at 0x69")) << rig.driver.error();
  EXPECT_TRUE(contains(rig.driver.error(), "NACK")) << rig.driver.error();
  EXPECT_TRUE(contains(rig.driver.error(), "AD0")) << rig.driver.error();
}

TEST(MpuDriverConfig, InvalidSettingsAreNamed) {
  struct Bad {
    void (*edit)(MpuConfig&);
    const char* says;
  };
  const Bad cases[] = {
      {[](MpuConfig& c) { c.gyro_full_scale_dps = 300; }, "gyro full scale 300 dps"},
      {[](MpuConfig& c) { c.accel_full_scale_g = 3; }, "accel full scale 3 g"},
      {[](MpuConfig& c) { c.dlpf = 7; }, "dlpf 7 outside 0..6"},
      {[](MpuConfig& c) { c.sample_rate_div = 256; }, "sample_rate_div 256"},
      {[](MpuConfig& c) { c.address = 0x50; }, "address 0x50"},
      {[](MpuConfig& c) { c.base_R_imu = Eigen::Quaterniond(2, 0, 0, 0); }, "not a unit quaternion"},
      {[](MpuConfig& c) { c.failures_before_reinit = 0; }, "failures_before_reinit 0"},
  };
  for (const Bad& b : cases) {
    MpuConfig c;
    b.edit(c);
    Rig rig(Chip::kMpu6050, c);
    EXPECT_FALSE(rig.driver.init(kStart));
    EXPECT_TRUE(contains(rig.driver.error(), b.says)) << rig.driver.error();
  }
}

struct RangeCase {
  int gyro_dps;
  int accel_g;
  std::uint8_t code;  // FS_SEL / AFS_SEL
  std::int16_t raw_one_g;
  std::int16_t raw_100_dps;
};

class MpuDriverRanges : public ::testing::TestWithParam<RangeCase> {};

TEST_P(MpuDriverRanges, ConfigurationRegistersAfterInit) {
  const RangeCase& p = GetParam();
  MpuConfig c;
  c.gyro_full_scale_dps = p.gyro_dps;
  c.accel_full_scale_g = p.accel_g;
  c.sample_rate_div = 4;
  c.dlpf = 2;
  Rig rig(Chip::kMpu6050, c);
  ASSERT_TRUE(rig.driver.init(kStart)) << rig.driver.error();
  EXPECT_EQ(rig.chip.reset_count(), 1);
  EXPECT_GE(rig.clock.now() - kStart, 100'000'000);  // the reset delay was waited out
  EXPECT_FALSE(rig.chip.asleep());
  EXPECT_EQ(rig.chip.peek(0x6B), 0x01);  // awake, PLL clock
  EXPECT_EQ(rig.chip.peek(0x19), 4);
  EXPECT_EQ(rig.chip.peek(0x1A), 2);
  EXPECT_EQ(rig.chip.peek(0x1B), p.code << 3);
  EXPECT_EQ(rig.chip.peek(0x1C), p.code << 3);
  EXPECT_EQ(rig.chip.gyro_fs_sel(), p.code);
  EXPECT_EQ(rig.chip.accel_fs_sel(), p.code);
  EXPECT_EQ(rig.chip.peek(0x37), 0x10);  // INT_RD_CLEAR, 50 us pulse
  EXPECT_EQ(rig.chip.peek(0x38), 0x01);  // DATA_RDY_EN
  EXPECT_EQ(rig.chip.peek(0x1D), 0x00);  // no ACCEL_CONFIG2 on a 6050
  EXPECT_DOUBLE_EQ(rig.driver.sample_rate_hz(), 200.0);
  EXPECT_EQ(rig.driver.sample_period_ns(), 5'000'000);
  EXPECT_DOUBLE_EQ(rig.chip.sample_rate_hz(), 200.0);
}

TEST_P(MpuDriverRanges, ScalesExactCountsToSi) {
  const RangeCase& p = GetParam();
  MpuConfig c;
  c.gyro_full_scale_dps = p.gyro_dps;
  c.accel_full_scale_g = p.accel_g;
  Rig rig(Chip::kMpu6050, c);
  ASSERT_TRUE(rig.driver.init(kStart)) << rig.driver.error();
  // One g and -1/2 g in counts; 100 deg/s and -100 deg/s.
  const std::int16_t accel[3] = {p.raw_one_g, static_cast<std::int16_t>(-p.raw_one_g / 2), 0};
  const std::int16_t gyro[3] = {p.raw_100_dps, 0, static_cast<std::int16_t>(-p.raw_100_dps)};
  ASSERT_TRUE(rig.chip.set_raw_sample(accel, 0, gyro));
  ImuReading r;
  ASSERT_EQ(rig.driver.read(1234, &r), MpuReadStatus::kOk) << rig.driver.error();
  EXPECT_EQ(r.stamp, 1234);
  EXPECT_NEAR(r.accel.x(), kG, 1e-12);
  EXPECT_NEAR(r.accel.y(), -0.5 * kG, 1e-12);
  EXPECT_EQ(r.accel.z(), 0.0);
  EXPECT_NEAR(r.gyro.x(), 100.0 * kDegToRad, 1e-12);
  EXPECT_NEAR(r.gyro.z(), -100.0 * kDegToRad, 1e-12);
  EXPECT_NEAR(r.temperature_c, 36.53, 1e-12);
  EXPECT_FALSE(r.accel_saturated);
  EXPECT_FALSE(r.gyro_saturated);
  EXPECT_NEAR(rig.driver.accel_full_scale_mps2(), p.accel_g * kG, p.accel_g * kG * 1e-4);
  EXPECT_NEAR(rig.driver.gyro_full_scale_rad_s(), p.gyro_dps * kDegToRad, p.gyro_dps * kDegToRad * 2e-3);
}

// LSB per g: 16384 >> code; LSB per deg/s: 131, 65.5, 32.8, 16.4.
INSTANTIATE_TEST_SUITE_P(FullScale, MpuDriverRanges,
                         ::testing::Values(RangeCase{250, 2, 0, 16384, 13100}, RangeCase{500, 4, 1, 8192, 6550},
                                           RangeCase{1000, 8, 2, 4096, 3280}, RangeCase{2000, 16, 3, 2048, 1640}));

TEST(MpuDriverConfig, Mpu6500AlsoGetsTheAccelFilter) {
  MpuConfig c;
  c.dlpf = 5;
  Rig rig(Chip::kMpu6500, c);
  ASSERT_TRUE(rig.driver.init(kStart)) << rig.driver.error();
  EXPECT_EQ(rig.chip.peek(0x1D), 5);  // A_DLPF_CFG = DLPF_CFG
  EXPECT_EQ(rig.chip.peek(0x1A), 5);
}

TEST(MpuDriverScaling, RoundTripsPhysicalValuesWithinHalfAnLsb) {
  MpuConfig c;
  c.gyro_full_scale_dps = 1000;
  c.accel_full_scale_g = 8;
  Rig rig(Chip::kMpu6050, c);
  ASSERT_TRUE(rig.driver.init(kStart));
  const double a[3] = {3.3, -71.0, 9.1};
  const double g[3] = {0.123, -15.0, 4.4};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 31.0));
  ImuReading r;
  ASSERT_EQ(rig.driver.read(1, &r), MpuReadStatus::kOk);
  const double a_lsb = kG / 4096.0, g_lsb = kDegToRad / 32.8;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.accel[i], a[i], 0.5 * a_lsb + 1e-12);
    EXPECT_NEAR(r.gyro[i], g[i], 0.5 * g_lsb + 1e-12);
  }
  EXPECT_NEAR(r.temperature_c, 31.0, 0.5 / 340.0);
}

// Mounted upside down (rotated pi about x): the chip's z points at the floor,
// so a level robot's chip reads -g on z; base_link must read +g.
TEST(MpuDriverMounting, UpsideDownImuReadsUprightInBaseLink) {
  MpuConfig c;
  c.base_R_imu = Eigen::Quaterniond(Eigen::AngleAxisd(3.14159265358979323846, Vector3d::UnitX()));
  Rig rig(Chip::kMpu6050, c);
  ASSERT_TRUE(rig.driver.init(kStart));
  const double a[3] = {0.5, 0.0, -kG};
  const double g[3] = {0.1, 0.2, 0.3};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 25.0));
  ImuReading r;
  ASSERT_EQ(rig.driver.read(1, &r), MpuReadStatus::kOk);
  const double a_lsb = kG / 8192.0, g_lsb = kDegToRad / 65.5;
  EXPECT_NEAR(r.accel.x(), 0.5, a_lsb);
  EXPECT_NEAR(r.accel.y(), 0.0, a_lsb);
  EXPECT_NEAR(r.accel.z(), kG, a_lsb);
  EXPECT_NEAR(r.gyro.x(), 0.1, g_lsb);
  EXPECT_NEAR(r.gyro.y(), -0.2, g_lsb);
  EXPECT_NEAR(r.gyro.z(), -0.3, g_lsb);
  EXPECT_EQ(r.raw[2], -8192);  // raw stays in chip axes
}

// Yawed 90 degrees: the chip's x is base_link's y.
TEST(MpuDriverMounting, YawedImuSwapsAxes) {
  MpuConfig c;
  c.base_R_imu = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Vector3d::UnitZ()));
  Rig rig(Chip::kMpu6050, c);
  ASSERT_TRUE(rig.driver.init(kStart));
  const double a[3] = {2.0, 0.0, kG};
  const double g[3] = {0.0, 0.0, 0.0};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 25.0));
  ImuReading r;
  ASSERT_EQ(rig.driver.read(1, &r), MpuReadStatus::kOk);
  const double a_lsb = kG / 8192.0;
  EXPECT_NEAR(r.accel.x(), 0.0, a_lsb);
  EXPECT_NEAR(r.accel.y(), 2.0, a_lsb);
  EXPECT_NEAR(r.accel.z(), kG, a_lsb);
}

struct TempCase {
  Chip chip;
  double celsius;
  std::int16_t raw;
};

class MpuDriverTemperature : public ::testing::TestWithParam<TempCase> {};

TEST_P(MpuDriverTemperature, PerModelFormula) {
  Rig rig(GetParam().chip);
  ASSERT_TRUE(rig.driver.init(kStart));
  const std::int16_t a[3] = {0, 0, 8192};
  const std::int16_t g[3] = {1, 2, 3};
  ASSERT_TRUE(rig.chip.set_raw_sample(a, GetParam().raw, g));
  ImuReading r;
  ASSERT_EQ(rig.driver.read(1, &r), MpuReadStatus::kOk) << rig.driver.error();
  EXPECT_NEAR(r.temperature_c, GetParam().celsius, 1e-9);
}

// 6050: raw / 340 + 36.53; 6500/9250: raw / 333.87 + 21.
INSTANTIATE_TEST_SUITE_P(Models, MpuDriverTemperature,
                         ::testing::Values(TempCase{Chip::kMpu6050, 36.53 - 3920.0 / 340.0, -3920},
                                           TempCase{Chip::kMpu6050, 36.53 + 3400.0 / 340.0, 3400},
                                           TempCase{Chip::kMpu6500, 21.0 + 1335.0 / 333.87, 1335},
                                           TempCase{Chip::kMpu9250, 21.0 - 6677.0 / 333.87, -6677}));

}  // namespace mpu_driver_test
