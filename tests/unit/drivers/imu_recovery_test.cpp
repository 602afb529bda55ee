// MpuImu recovery: frozen data and exhausted NACK retries end in a re-init
// and samples resume; a chip that does not come back is retried with a
// back-off; start() failures and a failing data-ready line are reported.
#include <gtest/gtest.h>

#include <string>

#include "drivers/imu/mpu_imu.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/mock/scripted_gpio.hpp"
#include "hal/mock/sim_clock.hpp"

namespace imu_recovery_test {

using rtfuse::TimeNs;
using rtfuse::drivers::ImuMeasurement;
using rtfuse::drivers::MpuImu;
using rtfuse::drivers::MpuImuConfig;
using rtfuse::drivers::StepResult;
using rtfuse::hal::HalStatus;
using rtfuse::hal::mock::MockI2cBus;
using rtfuse::sim::MpuRegisterFile;
using rtfuse::hal::mock::ScriptedEdgeSource;
using rtfuse::hal::mock::SimClock;
using Chip = rtfuse::sim::MpuChip;

constexpr double kG = 9.80665;
constexpr TimeNs kMs = 1'000'000;

struct Rig {
  explicit Rig(const MpuImuConfig& cfg) : chip(Chip::kMpu9250), clock(2'000 * kMs), imu(cfg, bus, &edges, clock) {
    EXPECT_TRUE(bus.attach(0x68, chip));
  }
  // A new sample on the chip and its data-ready edge 10 ms after the last.
  StepResult sample() {
    ++n;
    const double a[3] = {1e-3 * n, 0.0, kG};
    const double g[3] = {0.0, 0.0, 0.0};
    (void)chip.set_sample(a, g, 30.0);
    t = std::max(t, clock.now()) + 10 * kMs;
    edges.push(t);
    return imu.step(20 * kMs, &m);
  }
  MpuRegisterFile chip;
  MockI2cBus bus;
  SimClock clock;
  ScriptedEdgeSource edges;
  MpuImu imu;
  ImuMeasurement m;
  TimeNs t = 0;
  int n = 0;
};

bool contains(const char* text, const char* part) { return std::string(text).find(part) != std::string::npos; }

TEST(MpuImuRecovery, FrozenChipIsReinitialisedAndSamplesResume) {
  MpuImuConfig c;
  c.chip.frozen_reads = 3;
  c.chip.failures_before_reinit = 2;
  Rig rig(c);
  ASSERT_TRUE(rig.imu.start()) << rig.imu.error();
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  rig.chip.set_frozen(true);
  EXPECT_EQ(rig.sample(), StepResult::kSample);         // the same bytes twice
  EXPECT_EQ(rig.sample(), StepResult::kFault);          // three times: frozen
  EXPECT_TRUE(contains(rig.imu.error(), "frozen")) << rig.imu.error();
  EXPECT_EQ(rig.sample(), StepResult::kReinitialised);  // second failure in a row
  EXPECT_EQ(rig.chip.reset_count(), 2);
  // Still frozen after the reset: the data registers stay at their reset value 0.
  EXPECT_EQ(rig.sample(), StepResult::kFault);
  rig.chip.set_frozen(false);
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  EXPECT_TRUE(rig.m.has_orientation);
  const auto s = rig.imu.stats();
  EXPECT_EQ(s.frozen, 2);
  EXPECT_EQ(s.impossible, 1);
  EXPECT_EQ(s.reinits, 1);
  EXPECT_EQ(s.samples, 3);
}

TEST(MpuImuRecovery, ExhaustedNackRetriesFaultThenReinitThenRecover) {
  MpuImuConfig c;
  c.chip.failures_before_reinit = 2;
  Rig rig(c);
  ASSERT_TRUE(rig.imu.start());
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  rig.chip.nack_next(6);  // two reads' worth of three attempts
  EXPECT_EQ(rig.sample(), StepResult::kFault);
  EXPECT_TRUE(contains(rig.imu.error(), "NACK")) << rig.imu.error();
  EXPECT_EQ(rig.sample(), StepResult::kReinitialised);
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  const auto s = rig.imu.stats();
  EXPECT_EQ(s.nacks, 2);
  EXPECT_EQ(s.reinits, 1);
  EXPECT_EQ(s.reinit_failures, 0);
  EXPECT_EQ(rig.chip.reset_count(), 2);
}

TEST(MpuImuRecovery, ChipGoneIsRetriedWithBackoffUntilItAnswers) {
  MpuImuConfig c;
  c.chip.failures_before_reinit = 1;
  c.reinit_backoff_ns = 500 * kMs;
  Rig rig(c);
  ASSERT_TRUE(rig.imu.start());
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  rig.bus.detach(0x68);  // unplugged
  EXPECT_EQ(rig.sample(), StepResult::kDown);  // read NACK -> re-init -> WHO_AM_I NACK
  EXPECT_TRUE(contains(rig.imu.error(), "WHO_AM_I")) << rig.imu.error();
  const TimeNs down_at = rig.clock.now();
  const std::int64_t transfers = rig.bus.total_transfers();
  // Inside the back-off: each step waits its timeout and touches no bus.
  for (int i = 0; i < 5; ++i) EXPECT_EQ(rig.imu.step(20 * kMs, &rig.m), StepResult::kDown);
  EXPECT_EQ(rig.bus.total_transfers(), transfers);
  EXPECT_EQ(rig.clock.now() - down_at, 100 * kMs);
  ASSERT_TRUE(rig.bus.attach(0x68, rig.chip));  // plugged back in
  int steps = 0;
  StepResult r = StepResult::kDown;
  while (r == StepResult::kDown && steps < 100) {
    r = rig.imu.step(20 * kMs, &rig.m);
    ++steps;
  }
  EXPECT_EQ(r, StepResult::kReinitialised);
  EXPECT_EQ(steps, 20);  // 400 ms more of back-off in 20 ms waits, then the attempt
  EXPECT_EQ(rig.sample(), StepResult::kSample);
  const auto s = rig.imu.stats();
  EXPECT_EQ(s.reinit_failures, 1);
  EXPECT_EQ(s.reinits, 1);
}

TEST(MpuImuRecovery, StartFailureIsReportedAndRetriedByStep) {
  MpuImuConfig c;
  c.chip.model = rtfuse::drivers::MpuModel::kMpu9250;
  c.reinit_backoff_ns = 100 * kMs;
  Rig rig(c);
  rig.chip.set_wrong_who_am_i(0x73);
  EXPECT_FALSE(rig.imu.start());
  EXPECT_TRUE(contains(rig.imu.error(), "WHO_AM_I reads 0x73")) << rig.imu.error();
  EXPECT_TRUE(contains(rig.imu.error(), "MPU-9255")) << rig.imu.error();
  EXPECT_EQ(rig.imu.step(50 * kMs, &rig.m), StepResult::kDown);
  rig.chip.clear_faults();
  EXPECT_EQ(rig.imu.step(50 * kMs, &rig.m), StepResult::kReinitialised);
  EXPECT_EQ(rig.sample(), StepResult::kSample);
}

TEST(MpuImuRecovery, FailingDataReadyLineIsAFaultThatWaitsItsTimeout) {
  Rig rig(MpuImuConfig{});
  ASSERT_TRUE(rig.imu.start());
  rig.edges.fail_next(HalStatus::kClosed, 2);
  const TimeNs before = rig.clock.now();
  EXPECT_EQ(rig.imu.step(20 * kMs, &rig.m), StepResult::kFault);
  EXPECT_EQ(rig.imu.step(20 * kMs, &rig.m), StepResult::kFault);
  EXPECT_EQ(rig.clock.now() - before, 40 * kMs);
  EXPECT_TRUE(contains(rig.imu.error(), "data-ready line")) << rig.imu.error();
  EXPECT_EQ(rig.imu.stats().edge_errors, 2);
  EXPECT_EQ(rig.sample(), StepResult::kSample);
}

TEST(MpuImuRecovery, FallingEdgesAreIgnored) {
  Rig rig(MpuImuConfig{});
  ASSERT_TRUE(rig.imu.start());
  rig.edges.push(rig.clock.now() + kMs, false);
  EXPECT_EQ(rig.imu.step(20 * kMs, &rig.m), StepResult::kDropped);
  EXPECT_EQ(rig.imu.stats().ignored_edges, 1);
  EXPECT_EQ(rig.imu.stats().reads, 0);
  EXPECT_EQ(rig.sample(), StepResult::kSample);
}

}  // namespace imu_recovery_test
