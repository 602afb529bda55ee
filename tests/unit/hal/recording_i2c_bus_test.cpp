#include "hal/recording_i2c_bus.hpp"

#include <gtest/gtest.h>

#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace recording_i2c_bus_test {

using rtfuse::SpscRing;
using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::HalStatus;
using rtfuse::hal::RecordingI2cBus;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuChip;
using rtfuse::sim::MpuRegisterFile;
using rtfuse::hal::mock::SimClock;
namespace mpu = rtfuse::sim::mpu;

constexpr std::uint8_t kAddr = 0x68;

struct Rig {
  Rig() { EXPECT_TRUE(bus.attach(kAddr, chip)); }
  BusEvent pop() {
    BusEvent ev;
    EXPECT_TRUE(ring.try_pop(ev));
    return ev;
  }
  SimClock clock{7'000};
  MpuRegisterFile chip{MpuChip::kMpu6500};
  MockI2cBus bus;
  SpscRing<BusEvent> ring{64};
  RecordingI2cBus rec{bus, ring, 1, &clock};
};

TEST(HalRecordingI2cBus, ReadRecordsTheBytesTheDriverGot) {
  Rig r;
  ASSERT_EQ(r.rec.write_register(kAddr, mpu::kPwrMgmt1, 0x01), HalStatus::kOk);
  const std::int16_t accel[3] = {1000, -2000, 16384};
  const std::int16_t gyro[3] = {-1, 2, -300};
  r.chip.set_raw_sample(accel, 25, gyro);
  std::uint8_t buf[14] = {};
  r.clock.set(9'000);
  ASSERT_EQ(r.rec.read_registers(kAddr, mpu::kAccelXoutH, buf, 14), HalStatus::kOk);
  EXPECT_EQ(buf[0], 0x03);  // 1000 = 0x03E8 big-endian
  EXPECT_EQ(buf[1], 0xE8);

  const BusEvent w = r.pop();
  EXPECT_EQ(w.kind, BusEventKind::kI2cWrite);
  EXPECT_EQ(w.address, kAddr);
  EXPECT_EQ(w.reg, mpu::kPwrMgmt1);
  EXPECT_EQ(w.value, 0x01);
  EXPECT_EQ(w.length, 1);
  EXPECT_EQ(w.time_ns, 7'000);
  const BusEvent rd = r.pop();
  EXPECT_EQ(rd.kind, BusEventKind::kI2cRead);
  EXPECT_EQ(rd.device, 1);
  EXPECT_EQ(rd.time_ns, 9'000);
  EXPECT_EQ(rd.reg, mpu::kAccelXoutH);
  EXPECT_EQ(rd.length, 14);
  EXPECT_EQ(rd.status, HalStatus::kOk);
  for (int i = 0; i < 14; ++i) EXPECT_EQ(rd.data[i], buf[i]) << i;
  EXPECT_EQ(rd.data[14], 0) << "bytes past the read stay zero";
}

TEST(HalRecordingI2cBus, FailuresAndRetriesAreRecorded) {
  Rig r;
  // One glitch, recovered by the bus's retry: kOk with the retry counter moved.
  r.bus.fail_next(HalStatus::kBusError, 1);
  std::uint8_t who = 0;
  ASSERT_EQ(r.rec.read_registers(kAddr, mpu::kWhoAmI, &who, 1), HalStatus::kOk);
  EXPECT_EQ(who, 0x70);
  const BusEvent ok = r.pop();
  EXPECT_EQ(ok.retries, 1);
  EXPECT_EQ(ok.data[0], 0x70);
  EXPECT_EQ(r.rec.retries(), 1);

  // No device at 0x50: a NACK after every attempt, nothing read.
  std::uint8_t buf[2] = {0xAA, 0xAA};
  EXPECT_EQ(r.rec.read_registers(0x50, 0x00, buf, 2), HalStatus::kNack);
  const BusEvent nack = r.pop();
  EXPECT_EQ(nack.status, HalStatus::kNack);
  EXPECT_EQ(nack.address, 0x50);
  EXPECT_EQ(nack.data[0], 0) << "nothing was read, nothing is recorded";
  EXPECT_EQ(nack.retries, r.bus.retries());
}

TEST(HalRecordingI2cBus, FullRingCountsAndCallsDoNotAllocate) {
  MpuRegisterFile chip(MpuChip::kMpu6050);
  MockI2cBus bus;
  ASSERT_TRUE(bus.attach(kAddr, chip));
  SpscRing<BusEvent> ring(4);
  RecordingI2cBus rec(bus, ring, 0);
  std::uint8_t buf[14];
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 10; ++i) rec.read_registers(kAddr, mpu::kAccelXoutH, buf, 14);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(rec.overflows(), 6);
  EXPECT_EQ(ring.size(), 4u);
}

}  // namespace recording_i2c_bus_test
