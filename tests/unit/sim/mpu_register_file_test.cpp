#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "support/alloc_counter.hpp"

namespace mpu_register_file_test {

using rtfuse::hal::HalStatus;
using rtfuse::hal::I2cRetryPolicy;
using rtfuse::hal::mock::I2cTransferRecord;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuChip;
using rtfuse::sim::MpuRegisterFile;
namespace mpu = rtfuse::sim::mpu;

constexpr double kG = 9.80665;
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr std::uint8_t kAddr = 0x68;

std::int16_t be16(const std::uint8_t* p) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>((p[0] << 8) | p[1]));
}

// A chip on a bus, awake, data-ready enabled: what a driver has after init.
struct Rig {
  explicit Rig(MpuChip model = MpuChip::kMpu6050) : chip(model) {
    EXPECT_TRUE(bus.attach(kAddr, chip));
    EXPECT_EQ(bus.write_register(kAddr, mpu::kPwrMgmt1, 0x01), HalStatus::kOk);
    EXPECT_EQ(bus.write_register(kAddr, mpu::kIntEnable, mpu::kDataRdyEn), HalStatus::kOk);
  }
  // Burst read of accel, temp, gyro as the driver does it.
  void read_block(std::int16_t out[7]) {
    std::uint8_t b[14];
    ASSERT_EQ(bus.read_registers(kAddr, mpu::kAccelXoutH, b, 14), HalStatus::kOk);
    for (int i = 0; i < 7; ++i) out[i] = be16(b + 2 * i);
  }
  MpuRegisterFile chip;
  MockI2cBus bus;
};

struct WhoCase {
  MpuChip model;
  std::uint8_t who;
  std::uint8_t pwr_reset;
};

class HalMockMpuModel : public ::testing::TestWithParam<WhoCase> {};

TEST_P(HalMockMpuModel, WhoAmIAndResetDefaults) {
  const WhoCase& p = GetParam();
  MpuRegisterFile chip(p.model);
  MockI2cBus bus;
  ASSERT_TRUE(bus.attach(0x69, chip));
  std::uint8_t v = 0;
  ASSERT_EQ(bus.read_registers(0x69, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, p.who);
  ASSERT_EQ(bus.read_registers(0x69, mpu::kPwrMgmt1, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, p.pwr_reset);

  // Configure everything a driver configures, then reset.
  const std::uint8_t writes[][2] = {{mpu::kPwrMgmt1, 0x01},    {mpu::kSmplrtDiv, 9},   {mpu::kConfig, 3},
                                    {mpu::kGyroConfig, 0x18}, {mpu::kAccelConfig, 0x10}, {mpu::kIntPinCfg, 0x10},
                                    {mpu::kIntEnable, 0x01}};
  for (const auto& w : writes) ASSERT_EQ(bus.write_register(0x69, w[0], w[1]), HalStatus::kOk);
  const double a[3] = {1.0, 2.0, 3.0};
  const double g[3] = {0.1, 0.2, 0.3};
  ASSERT_TRUE(chip.set_sample(a, g, 30.0));
  ASSERT_EQ(bus.write_register(0x69, mpu::kPwrMgmt1, 0x80), HalStatus::kOk);
  EXPECT_EQ(chip.reset_count(), 1);
  ASSERT_EQ(bus.read_registers(0x69, mpu::kPwrMgmt1, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, p.pwr_reset);  // DEVICE_RESET cleared itself
  for (std::uint8_t reg : {mpu::kSmplrtDiv, mpu::kConfig, mpu::kGyroConfig, mpu::kAccelConfig, mpu::kIntPinCfg,
                           mpu::kIntEnable, mpu::kIntStatus, mpu::kAccelXoutH, mpu::kGyroZoutL}) {
    EXPECT_EQ(chip.peek(reg), 0) << "reg 0x" << std::hex << int(reg);
  }
  EXPECT_EQ(chip.peek(mpu::kWhoAmI), p.who);
}

INSTANTIATE_TEST_SUITE_P(Models, HalMockMpuModel,
                         ::testing::Values(WhoCase{MpuChip::kMpu6050, 0x68, 0x40},
                                           WhoCase{MpuChip::kMpu6500, 0x70, 0x01},
                                           WhoCase{MpuChip::kMpu9250, 0x71, 0x01}));

TEST(HalMockMpu, AsleepChipDoesNotSampleUntilWoken) {
  MpuRegisterFile chip(MpuChip::kMpu6050);
  EXPECT_TRUE(chip.asleep());
  const double a[3] = {0, 0, kG};
  const double g[3] = {0, 0, 0};
  ASSERT_EQ(chip.i2c_write(mpu::kIntEnable, 0x01), HalStatus::kOk);
  EXPECT_FALSE(chip.set_sample(a, g, 25.0));
  EXPECT_EQ(chip.peek16(mpu::kAccelXoutH + 4), 0);
  EXPECT_FALSE(chip.data_ready_pending());
  ASSERT_EQ(chip.i2c_write(mpu::kPwrMgmt1, 0x00), HalStatus::kOk);
  EXPECT_TRUE(chip.set_sample(a, g, 25.0));
  EXPECT_EQ(chip.peek16(mpu::kAccelXoutH + 4), 16384);
}

struct ScaleCase {
  int fs_sel;
  std::int16_t accel_one_g;
  std::int16_t accel_minus_half_g;
  std::int16_t gyro_100dps;
  std::int16_t gyro_minus_10dps;
};

class HalMockMpuScale : public ::testing::TestWithParam<ScaleCase> {};

TEST_P(HalMockMpuScale, ExactRawValuesAtEachRange) {
  const ScaleCase& p = GetParam();
  Rig rig;
  const auto sel = static_cast<std::uint8_t>(p.fs_sel << 3);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kAccelConfig, sel), HalStatus::kOk);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kGyroConfig, sel), HalStatus::kOk);
  EXPECT_EQ(rig.chip.accel_fs_sel(), p.fs_sel);
  EXPECT_EQ(rig.chip.gyro_fs_sel(), p.fs_sel);
  const double a[3] = {kG, -0.5 * kG, 0.0};
  const double g[3] = {100.0 * kDegToRad, -10.0 * kDegToRad, 0.0};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 36.53));
  std::int16_t r[7];
  rig.read_block(r);
  EXPECT_EQ(r[0], p.accel_one_g);
  EXPECT_EQ(r[1], p.accel_minus_half_g);
  EXPECT_EQ(r[2], 0);
  EXPECT_EQ(r[3], 0);  // 36.53 C is raw 0 on the 6050
  EXPECT_EQ(r[4], p.gyro_100dps);
  EXPECT_EQ(r[5], p.gyro_minus_10dps);
  EXPECT_EQ(r[6], 0);
  EXPECT_DOUBLE_EQ(mpu::accel_lsb_per_g(p.fs_sel), p.accel_one_g);
}

INSTANTIATE_TEST_SUITE_P(Ranges, HalMockMpuScale,
                         ::testing::Values(ScaleCase{0, 16384, -8192, 13100, -1310},
                                           ScaleCase{1, 8192, -4096, 6550, -655},
                                           ScaleCase{2, 4096, -2048, 3280, -328},
                                           ScaleCase{3, 2048, -1024, 1640, -164}));

TEST(HalMockMpu, SaturatesAtFullScaleLikeTheChip) {
  Rig rig;
  const double a[3] = {2.0 * kG, -3.0 * kG, 1.999 * kG};
  const double g[3] = {300.0 * kDegToRad, -251.0 * kDegToRad, 1e9};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 500.0));
  std::int16_t r[7];
  rig.read_block(r);
  EXPECT_EQ(r[0], 32767);
  EXPECT_EQ(r[1], -32767);
  EXPECT_EQ(r[2], 32752);  // 1.999 * 16384 = 32751.6: just inside
  EXPECT_EQ(r[3], 32767);  // temperature saturates too
  EXPECT_EQ(r[4], 32767);
  EXPECT_EQ(r[5], -32767);
  EXPECT_EQ(r[6], 32767);
}

TEST(HalMockMpu, TemperatureScalingPerModel) {
  Rig r6050(MpuChip::kMpu6050);
  Rig r6500(MpuChip::kMpu6500);
  Rig r9250(MpuChip::kMpu9250);
  const double a[3] = {0, 0, 0};
  const double g[3] = {0, 0, 0};
  ASSERT_TRUE(r6050.chip.set_sample(a, g, 25.0));
  ASSERT_TRUE(r6500.chip.set_sample(a, g, 25.0));
  ASSERT_TRUE(r9250.chip.set_sample(a, g, 21.0));
  // (25 - 36.53) * 340 = -3920.2; (25 - 21) * 333.87 = 1335.48
  EXPECT_EQ(r6050.chip.peek16(mpu::kTempOutH), -3920);
  EXPECT_EQ(r6500.chip.peek16(mpu::kTempOutH), 1335);
  EXPECT_EQ(r9250.chip.peek16(mpu::kTempOutH), 0);
  EXPECT_NEAR(mpu::temperature_c(MpuChip::kMpu6050, -3920), 25.0, 0.5 / 340.0);
  EXPECT_NEAR(mpu::temperature_c(MpuChip::kMpu6500, 1335), 25.0, 0.5 / 333.87);
}

TEST(HalMockMpu, BurstReadIsBigEndianInRegisterOrder) {
  Rig rig;
  const std::int16_t acc[3] = {0x0102, -2, 0x7F00};
  const std::int16_t gyr[3] = {-32768, 0x1234, 1};
  ASSERT_TRUE(rig.chip.set_raw_sample(acc, 0x0A0B, gyr));
  std::uint8_t b[14];
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 14), HalStatus::kOk);
  const std::uint8_t expect[14] = {0x01, 0x02, 0xFF, 0xFE, 0x7F, 0x00, 0x0A, 0x0B, 0x80, 0x00, 0x12, 0x34, 0x00, 0x01};
  for (int i = 0; i < 14; ++i) EXPECT_EQ(b[i], expect[i]) << "byte " << i;
}

TEST(HalMockMpu, DataReadyIsRaisedOnlyWhenEnabledAndClearedByReadingStatus) {
  Rig rig;
  const double a[3] = {0, 0, kG};
  const double g[3] = {0, 0, 0};
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kIntEnable, 0x00), HalStatus::kOk);
  EXPECT_FALSE(rig.chip.set_sample(a, g, 25.0));
  EXPECT_FALSE(rig.chip.data_ready_pending());
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kIntEnable, mpu::kDataRdyEn), HalStatus::kOk);
  EXPECT_TRUE(rig.chip.set_sample(a, g, 25.0));
  EXPECT_TRUE(rig.chip.data_ready_pending());
  // Reading the data alone does not clear it (INT_RD_CLEAR = 0).
  std::int16_t r[7];
  rig.read_block(r);
  EXPECT_TRUE(rig.chip.data_ready_pending());
  std::uint8_t st = 0;
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kIntStatus, &st, 1), HalStatus::kOk);
  EXPECT_EQ(st & mpu::kDataRdyInt, mpu::kDataRdyInt);
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kIntStatus, &st, 1), HalStatus::kOk);
  EXPECT_EQ(st, 0);  // cleared on read
  // A burst starting before INT_STATUS that covers it clears it too.
  EXPECT_TRUE(rig.chip.set_sample(a, g, 25.0));
  std::uint8_t b[16];
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kIntEnable, b, 16), HalStatus::kOk);
  EXPECT_EQ(b[2], mpu::kDataRdyInt);
  EXPECT_FALSE(rig.chip.data_ready_pending());
}

TEST(HalMockMpu, IntRdClearMakesAnyReadClearStatus) {
  Rig rig;
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kIntPinCfg, mpu::kIntRdClear), HalStatus::kOk);
  const double a[3] = {0, 0, kG};
  const double g[3] = {0, 0, 0};
  EXPECT_TRUE(rig.chip.set_sample(a, g, 25.0));
  std::int16_t r[7];
  rig.read_block(r);
  EXPECT_FALSE(rig.chip.data_ready_pending());
}

TEST(HalMockMpu, ReadOnlyRegistersIgnoreWrites) {
  Rig rig;
  const std::int16_t acc[3] = {1, 2, 3};
  const std::int16_t gyr[3] = {4, 5, 6};
  ASSERT_TRUE(rig.chip.set_raw_sample(acc, 7, gyr));
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kWhoAmI, 0x00), HalStatus::kOk);  // acknowledged
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kAccelXoutH + 1, 0x55), HalStatus::kOk);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kIntStatus, 0x00), HalStatus::kOk);
  EXPECT_EQ(rig.chip.peek(mpu::kWhoAmI), 0x68);
  EXPECT_EQ(rig.chip.peek16(mpu::kAccelXoutH), 1);
  EXPECT_TRUE(rig.chip.data_ready_pending());
}

TEST(HalMockMpu, NackInjectionIsRetriedWithinThePolicyAndLeavesTheBufferAlone) {
  Rig rig;
  rig.bus.clear_log();
  const std::int64_t retries_before = rig.bus.retries();
  std::uint8_t v = 0xEE;
  rig.chip.nack_next(2);  // attempts = 3 by default: the third one passes
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, 0x68);
  EXPECT_EQ(rig.bus.retries() - retries_before, 2);
  ASSERT_EQ(rig.bus.transfer_count(), 1);
  EXPECT_EQ(rig.bus.transfer(0).attempts, 3);

  v = 0xEE;
  rig.chip.nack_next(3);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kNack);
  EXPECT_EQ(v, 0xEE);
  EXPECT_EQ(rig.bus.retries() - retries_before, 2);  // failures that never recovered are not retries
  EXPECT_STRNE(rig.bus.last_error(), "");
  EXPECT_EQ(rig.chip.nacks_pending(), 0);

  // A NACKed write changes nothing.
  rig.chip.nack_next(5);
  EXPECT_EQ(rig.bus.write_register(kAddr, mpu::kGyroConfig, 0x18), HalStatus::kNack);
  EXPECT_EQ(rig.chip.gyro_fs_sel(), 0);
  EXPECT_EQ(rig.chip.nacks_pending(), 2);
}

TEST(HalMockMpu, NackedReadDoesNotClearDataReady) {
  Rig rig;
  const double a[3] = {0, 0, kG};
  const double g[3] = {0, 0, 0};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 25.0));
  MockI2cBus one_try(I2cRetryPolicy{1});
  ASSERT_TRUE(one_try.attach(kAddr, rig.chip));
  rig.chip.nack_next(1);
  std::uint8_t st = 0;
  EXPECT_EQ(one_try.read_registers(kAddr, mpu::kIntStatus, &st, 1), HalStatus::kNack);
  EXPECT_TRUE(rig.chip.data_ready_pending());
}

TEST(HalMockMpu, AbsentAddressIsNack) {
  MpuRegisterFile chip(MpuChip::kMpu6050);
  MockI2cBus bus;
  ASSERT_TRUE(bus.attach(0x68, chip));
  std::uint8_t v = 0xEE;
  EXPECT_EQ(bus.read_registers(0x69, mpu::kWhoAmI, &v, 1), HalStatus::kNack);
  EXPECT_EQ(v, 0xEE);
  EXPECT_EQ(bus.write_register(0x69, mpu::kPwrMgmt1, 0x00), HalStatus::kNack);
  ASSERT_EQ(bus.transfer_count(), 2);
  EXPECT_EQ(bus.transfer(0).status, HalStatus::kNack);
  EXPECT_EQ(bus.transfer(0).attempts, 3);  // a missing device NACKs every try
  EXPECT_EQ(bus.retries(), 0);
  bus.detach(0x68);
  EXPECT_EQ(bus.read_registers(0x68, mpu::kWhoAmI, &v, 1), HalStatus::kNack);
}

TEST(HalMockMpu, AttachRejectsDuplicatesAndInvalidAddresses) {
  MpuRegisterFile a(MpuChip::kMpu6050);
  MpuRegisterFile b(MpuChip::kMpu6500);
  MockI2cBus bus;
  EXPECT_TRUE(bus.attach(0x68, a));
  EXPECT_FALSE(bus.attach(0x68, b));
  EXPECT_FALSE(bus.attach(0x80, b));
  EXPECT_TRUE(bus.attach(0x69, b));
  std::uint8_t v = 0;
  ASSERT_EQ(bus.read_registers(0x69, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, 0x70);
}

TEST(HalMockMpu, BusFaultsFollowTheRetryPolicy) {
  Rig rig;
  std::uint8_t v = 0;
  rig.bus.fail_next(HalStatus::kTimeout, 1);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kTimeout);
  EXPECT_EQ(rig.bus.transfer(rig.bus.transfer_count() - 1).attempts, 1);  // timeouts are not retried
  rig.bus.fail_next(HalStatus::kBusError, 1);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(rig.bus.retries(), 1);
  EXPECT_EQ(v, 0x68);
}

TEST(HalMockMpu, InvalidReadLengthIsAnIoError) {
  Rig rig;
  std::uint8_t b[65] = {};
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 0), HalStatus::kIoError);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 65), HalStatus::kIoError);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, nullptr, 1), HalStatus::kIoError);
  EXPECT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 64), HalStatus::kOk);
}

TEST(HalMockMpu, TransferLogRecordsWhatTheDriverAskedFor) {
  Rig rig;  // two writes so far
  std::uint8_t b[14];
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 14), HalStatus::kOk);
  ASSERT_EQ(rig.bus.transfer_count(), 3);
  const I2cTransferRecord& w = rig.bus.transfer(0);
  EXPECT_EQ(w.address, kAddr);
  EXPECT_EQ(w.reg, mpu::kPwrMgmt1);
  EXPECT_TRUE(w.write);
  EXPECT_EQ(w.value, 0x01);
  EXPECT_EQ(w.length, 1);
  const I2cTransferRecord& r = rig.bus.transfer(2);
  EXPECT_FALSE(r.write);
  EXPECT_EQ(r.reg, mpu::kAccelXoutH);
  EXPECT_EQ(r.length, 14);
  EXPECT_EQ(r.status, HalStatus::kOk);
  EXPECT_EQ(r.attempts, 1);

  MockI2cBus small(I2cRetryPolicy{}, 2);
  ASSERT_TRUE(small.attach(kAddr, rig.chip));
  for (std::uint8_t reg = 0x19; reg <= 0x1C; ++reg) ASSERT_EQ(small.write_register(kAddr, reg, 0), HalStatus::kOk);
  ASSERT_EQ(small.transfer_count(), 2);  // the most recent two
  EXPECT_EQ(small.transfer(0).reg, 0x1B);
  EXPECT_EQ(small.transfer(1).reg, 0x1C);
  EXPECT_EQ(small.total_transfers(), 4);
}

TEST(HalMockMpu, WrongWhoAmISurvivesResetUntilCleared) {
  Rig rig(MpuChip::kMpu9250);
  rig.chip.set_wrong_who_am_i(0x73);
  std::uint8_t v = 0;
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, 0x73);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kPwrMgmt1, 0x80), HalStatus::kOk);
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, 0x73);
  rig.chip.clear_faults();
  ASSERT_EQ(rig.bus.read_registers(kAddr, mpu::kWhoAmI, &v, 1), HalStatus::kOk);
  EXPECT_EQ(v, 0x71);
}

TEST(HalMockMpu, FrozenChipKeepsSignallingWithStaleData) {
  Rig rig;
  const double a1[3] = {0, 0, kG};
  const double a2[3] = {kG, 0, 0};
  const double g[3] = {0, 0, 0};
  ASSERT_TRUE(rig.chip.set_sample(a1, g, 25.0));
  rig.chip.set_frozen(true);
  EXPECT_TRUE(rig.chip.set_sample(a2, g, 30.0));
  std::int16_t r[7];
  rig.read_block(r);
  EXPECT_EQ(r[0], 0);
  EXPECT_EQ(r[2], 16384);
  rig.chip.set_frozen(false);
  EXPECT_TRUE(rig.chip.set_sample(a2, g, 30.0));
  rig.read_block(r);
  EXPECT_EQ(r[0], 16384);
  EXPECT_EQ(r[2], 0);
}

TEST(HalMockMpu, NonFiniteSampleIsRejected) {
  Rig rig;
  const double a[3] = {0, std::numeric_limits<double>::quiet_NaN(), 0};
  const double g[3] = {0, 0, std::numeric_limits<double>::infinity()};
  const double ok[3] = {0, 0, 0};
  EXPECT_FALSE(rig.chip.set_sample(a, ok, 25.0));
  EXPECT_FALSE(rig.chip.set_sample(ok, g, 25.0));
  EXPECT_FALSE(rig.chip.set_sample(ok, ok, std::nan("")));
  EXPECT_FALSE(rig.chip.data_ready_pending());
}

TEST(HalMockMpu, SampleRateFollowsDividerAndDlpf) {
  Rig rig;
  EXPECT_DOUBLE_EQ(rig.chip.sample_rate_hz(), 8000.0);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kConfig, 3), HalStatus::kOk);
  ASSERT_EQ(rig.bus.write_register(kAddr, mpu::kSmplrtDiv, 4), HalStatus::kOk);
  EXPECT_DOUBLE_EQ(rig.chip.sample_rate_hz(), 200.0);
}

TEST(HalMockMpu, SteadyStateSampleAndReadDoesNotAllocate) {
  Rig rig;
  double a[3] = {0, 0, kG};
  const double g[3] = {0.01, -0.02, 0.03};
  std::uint8_t b[14];
  std::uint8_t st;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    a[0] = 0.001 * i;
    (void)rig.chip.set_sample(a, g, 25.0);
    (void)rig.bus.read_registers(kAddr, mpu::kIntStatus, &st, 1);
    (void)rig.bus.read_registers(kAddr, mpu::kAccelXoutH, b, 14);
  }
  EXPECT_EQ(scope.count(), 0U);
}

}  // namespace mpu_register_file_test
