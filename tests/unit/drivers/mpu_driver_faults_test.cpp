// MpuDriver faults: saturation, frozen data, NACK / bus errors, impossible
// values, the re-init request, and no allocation in read().
#include <gtest/gtest.h>

#include <string>

#include "drivers/imu/mpu_driver.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace mpu_driver_faults_test {

using rtfuse::drivers::ImuReading;
using rtfuse::drivers::MpuConfig;
using rtfuse::drivers::MpuDriver;
using rtfuse::drivers::MpuSaturation;
using rtfuse::drivers::MpuReadStatus;
using rtfuse::hal::HalStatus;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuRegisterFile;
using rtfuse::hal::mock::SimClock;
using Chip = rtfuse::sim::MpuChip;

constexpr double kG = 9.80665;

struct Rig {
  explicit Rig(MpuConfig cfg = {}, Chip model = Chip::kMpu6050)
      : chip(model), clock(1'000'000'000), driver(bus, clock, cfg) {
    EXPECT_TRUE(bus.attach(0x68, chip));
    EXPECT_TRUE(driver.init(clock.now())) << driver.error();
  }
  // A distinct sample each call (real sensors never repeat 14 bytes).
  void sample(double x = 0.0) {
    ++n;
    const double a[3] = {x + 0.001 * n, 0.0, kG};
    const double g[3] = {0.0, 0.0, 0.001 * n};
    ASSERT_TRUE(chip.set_sample(a, g, 25.0));
  }
  MpuReadStatus read() { return driver.read(++stamp, &out); }
  MpuRegisterFile chip;
  MockI2cBus bus;
  SimClock clock;
  MpuDriver driver;
  ImuReading out;
  rtfuse::TimeNs stamp = 0;
  int n = 0;
};

bool contains(const char* text, const char* part) { return std::string(text).find(part) != std::string::npos; }

TEST(MpuDriverSaturation, AccelAtFullScaleIsFlaggedNotDropped) {
  MpuConfig c;
  c.accel_full_scale_g = 2;
  Rig rig(c);
  const double a[3] = {3.0 * kG, 0.0, kG};  // beyond +-2 g on x
  const double g[3] = {0.1, 0.0, 0.0};
  ASSERT_TRUE(rig.chip.set_sample(a, g, 25.0));
  ASSERT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_TRUE(rig.out.accel_saturated);
  EXPECT_FALSE(rig.out.gyro_saturated);
  EXPECT_EQ(rig.out.raw[0], 32767);
  EXPECT_EQ(rig.driver.stats().saturated, 1);
  EXPECT_EQ(rig.driver.stats().consecutive_failures, 0);
}

TEST(MpuDriverSaturation, GyroAtNegativeFullScaleIsFlagged) {
  Rig rig;
  for (std::int16_t neg : {std::int16_t{-32767}, std::int16_t{-32768}}) {
    const std::int16_t a[3] = {10, 20, 8192};
    const std::int16_t g[3] = {5, neg, 7};
    ASSERT_TRUE(rig.chip.set_raw_sample(a, 0, g));
    ASSERT_EQ(rig.read(), MpuReadStatus::kOk);
    EXPECT_TRUE(rig.out.gyro_saturated) << neg;
    EXPECT_FALSE(rig.out.accel_saturated) << neg;
  }
  // One count inside full scale is a measurement.
  const std::int16_t a[3] = {10, 20, 8192};
  const std::int16_t g[3] = {5, -32766, 32766};
  ASSERT_TRUE(rig.chip.set_raw_sample(a, 0, g));
  ASSERT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_FALSE(rig.out.gyro_saturated);
  EXPECT_EQ(rig.driver.stats().saturated, 2);
}

TEST(MpuDriverSaturation, RejectPolicyDropsTheSampleWithoutCountingAFault) {
  MpuConfig c;
  c.saturation = MpuSaturation::kReject;
  c.gyro_full_scale_dps = 250;
  Rig rig(c);
  const double a[3] = {0.0, 0.0, kG};
  const double g[3] = {0.0, 0.0, 5.0};  // 286 deg/s
  ASSERT_TRUE(rig.chip.set_sample(a, g, 25.0));
  rig.out.stamp = -1;
  EXPECT_EQ(rig.read(), MpuReadStatus::kSaturated);
  EXPECT_EQ(rig.out.stamp, -1);  // untouched
  EXPECT_EQ(rig.driver.stats().saturated, 1);
  EXPECT_EQ(rig.driver.stats().consecutive_failures, 0);
  EXPECT_FALSE(rig.driver.needs_reinit());
}

TEST(MpuDriverFrozen, SameBytesNTimesIsFrozenThenReinitRecovers) {
  MpuConfig c;
  c.frozen_reads = 3;
  c.failures_before_reinit = 2;
  Rig rig(c);
  rig.sample();
  ASSERT_EQ(rig.read(), MpuReadStatus::kOk);
  rig.chip.set_frozen(true);
  rig.sample();  // data registers keep the previous bytes
  EXPECT_EQ(rig.read(), MpuReadStatus::kOk);  // seen twice: could still be a coincidence
  rig.sample();
  EXPECT_EQ(rig.read(), MpuReadStatus::kFrozen);  // three times
  EXPECT_FALSE(rig.driver.needs_reinit());
  EXPECT_TRUE(contains(rig.driver.error(), "frozen")) << rig.driver.error();
  rig.sample();
  EXPECT_EQ(rig.read(), MpuReadStatus::kFrozen);
  EXPECT_TRUE(rig.driver.needs_reinit());
  EXPECT_EQ(rig.driver.stats().frozen, 2);
  EXPECT_EQ(rig.driver.stats().reinit_requests, 1);

  rig.chip.set_frozen(false);
  ASSERT_TRUE(rig.driver.init(rig.clock.now())) << rig.driver.error();
  EXPECT_FALSE(rig.driver.needs_reinit());
  EXPECT_EQ(rig.chip.reset_count(), 2);
  rig.sample();
  EXPECT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_EQ(rig.driver.stats().good_reads, 3);
}

TEST(MpuDriverFrozen, ZeroDisablesTheCheck) {
  MpuConfig c;
  c.frozen_reads = 0;
  Rig rig(c);
  rig.sample();
  for (int i = 0; i < 20; ++i) EXPECT_EQ(rig.read(), MpuReadStatus::kOk);
}

TEST(MpuDriverBus, NackRetriesThenFailureThenReinitRequest) {
  MpuConfig c;
  c.failures_before_reinit = 3;
  Rig rig(c);
  rig.sample();
  rig.chip.nack_next(2);  // the bus's 3 attempts absorb two NACKs
  EXPECT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_EQ(rig.driver.stats().nacks, 0);

  rig.out.stamp = -1;
  rig.chip.nack_next(3);  // retries exhausted
  EXPECT_EQ(rig.read(), MpuReadStatus::kNack);
  EXPECT_EQ(rig.out.stamp, -1);
  EXPECT_TRUE(contains(rig.driver.error(), "NACK")) << rig.driver.error();
  rig.bus.fail_next(HalStatus::kBusError, 3);
  EXPECT_EQ(rig.read(), MpuReadStatus::kBusError);
  EXPECT_FALSE(rig.driver.needs_reinit());
  rig.bus.fail_next(HalStatus::kTimeout, 1);  // not retried by the bus
  EXPECT_EQ(rig.read(), MpuReadStatus::kTimeout);
  EXPECT_TRUE(rig.driver.needs_reinit());
  const auto& s = rig.driver.stats();
  EXPECT_EQ(s.nacks, 1);
  EXPECT_EQ(s.bus_errors, 1);
  EXPECT_EQ(s.timeouts, 1);
  EXPECT_EQ(s.consecutive_failures, 3);
  EXPECT_EQ(s.reinit_requests, 1);

  // A good read clears the request: the fault was transient.
  rig.sample();
  EXPECT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_FALSE(rig.driver.needs_reinit());
  EXPECT_EQ(rig.driver.stats().consecutive_failures, 0);
}

TEST(MpuDriverImpossible, AllZeroAllOnesAndHotTemperature) {
  Rig rig;
  const std::int16_t zero[3] = {0, 0, 0};
  ASSERT_TRUE(rig.chip.set_raw_sample(zero, 0, zero));
  EXPECT_EQ(rig.read(), MpuReadStatus::kImpossible);
  EXPECT_TRUE(contains(rig.driver.error(), "all 0x00")) << rig.driver.error();

  const std::int16_t ones[3] = {-1, -1, -1};
  ASSERT_TRUE(rig.chip.set_raw_sample(ones, -1, ones));
  EXPECT_EQ(rig.read(), MpuReadStatus::kImpossible);
  EXPECT_TRUE(contains(rig.driver.error(), "all 0xff")) << rig.driver.error();

  const std::int16_t a[3] = {1, 2, 8192};
  ASSERT_TRUE(rig.chip.set_raw_sample(a, 20000, a));  // 95.4 C on a 6050
  EXPECT_EQ(rig.read(), MpuReadStatus::kImpossible);
  EXPECT_TRUE(contains(rig.driver.error(), "temperature 95 C")) << rig.driver.error();
  ASSERT_TRUE(rig.chip.set_raw_sample(a, -26000, a));  // -39.9 C: cold but possible
  EXPECT_EQ(rig.read(), MpuReadStatus::kOk);
  EXPECT_EQ(rig.driver.stats().impossible, 3);
}

TEST(MpuDriverImpossible, AsleepChipReadsZerosAfterAReset) {
  Rig rig;
  rig.sample();
  ASSERT_EQ(rig.read(), MpuReadStatus::kOk);
  // Someone reset the chip behind the driver's back: asleep, data registers 0.
  ASSERT_EQ(rig.bus.write_register(0x68, 0x6B, 0x80), HalStatus::kOk);
  const double a[3] = {0.0, 0.0, kG};
  const double g[3] = {0.0, 0.0, 0.0};
  EXPECT_FALSE(rig.chip.set_sample(a, g, 25.0));  // asleep: no sample
  EXPECT_EQ(rig.read(), MpuReadStatus::kImpossible);
}

TEST(MpuDriverState, ReadBeforeInitIsRefused) {
  MpuRegisterFile chip(Chip::kMpu6050);
  MockI2cBus bus;
  SimClock clock;
  ASSERT_TRUE(bus.attach(0x68, chip));
  MpuDriver d(bus, clock, MpuConfig{});
  ImuReading r;
  EXPECT_EQ(d.read(1, &r), MpuReadStatus::kNotInitialised);
  EXPECT_EQ(bus.total_transfers(), 0);
}

TEST(MpuDriverRealtime, ReadDoesNotAllocate) {
  Rig rig;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 500; ++i) {
    const double a[3] = {0.001 * i, 0.0, kG};
    const double g[3] = {0.0, 0.002 * i, 0.0};
    (void)rig.chip.set_sample(a, g, 25.0);
    (void)rig.read();
  }
  rig.chip.nack_next(3);
  (void)rig.read();
  const std::int16_t zero[3] = {0, 0, 0};
  (void)rig.chip.set_raw_sample(zero, 20000, zero);
  (void)rig.read();
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(rig.driver.stats().good_reads, 500);
}

}  // namespace mpu_driver_faults_test
