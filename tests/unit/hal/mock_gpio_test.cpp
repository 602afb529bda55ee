#include "hal/mock/scripted_gpio.hpp"

#include <gtest/gtest.h>

#include "hal/mock/sim_clock.hpp"

#include "support/alloc_counter.hpp"

namespace mock_gpio_test {

using rtfuse::TimeNs;
using rtfuse::hal::GpioEdge;
using rtfuse::hal::HalStatus;
using rtfuse::hal::mock::RecordingGpioOutput;
using rtfuse::hal::mock::ScriptedEdgeSource;

constexpr TimeNs kMs = 1'000'000;

TEST(HalMockGpio, EdgesComeOutInOrderWithTheirStamps) {
  ScriptedEdgeSource src;
  ASSERT_TRUE(src.push(10 * kMs, true));
  ASSERT_TRUE(src.push(GpioEdge{12 * kMs, false}));
  ASSERT_TRUE(src.push(15 * kMs));
  EXPECT_EQ(src.pending(), 3);
  GpioEdge e;
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 10 * kMs);
  EXPECT_TRUE(e.rising);
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 12 * kMs);
  EXPECT_FALSE(e.rising);
  ASSERT_EQ(src.wait_edge(5 * kMs, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 15 * kMs);
  EXPECT_EQ(src.delivered(), 3);
}

TEST(HalMockGpio, NoEdgeIsATimeoutAndLeavesTheOutputAlone) {
  ScriptedEdgeSource src;
  GpioEdge e{77, false};
  EXPECT_EQ(src.wait_edge(0, &e), HalStatus::kTimeout);
  EXPECT_EQ(src.wait_edge(10 * kMs, &e), HalStatus::kTimeout);
  EXPECT_EQ(e.stamp, 77);
  EXPECT_FALSE(e.rising);
}

TEST(HalMockGpio, FullQueueDropsAndCountsThenWraps) {
  ScriptedEdgeSource src(2);
  EXPECT_TRUE(src.push(1));
  EXPECT_TRUE(src.push(2));
  EXPECT_FALSE(src.push(3));
  EXPECT_EQ(src.dropped(), 1);
  GpioEdge e;
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_TRUE(src.push(4));
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 2);
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 4);
  src.push(5);
  src.clear();
  EXPECT_EQ(src.wait_edge(0, &e), HalStatus::kTimeout);
}

TEST(HalMockGpio, WithAClockFutureEdgesWaitForTheirTime) {
  rtfuse::hal::mock::SimClock clock(100 * kMs);
  ScriptedEdgeSource src(16, &clock);
  src.push(105 * kMs);
  src.push(110 * kMs);
  GpioEdge e;
  EXPECT_EQ(src.wait_edge(0, &e), HalStatus::kTimeout);       // not yet
  EXPECT_EQ(src.wait_edge(4 * kMs, &e), HalStatus::kTimeout);  // not within the wait either
  ASSERT_EQ(src.wait_edge(5 * kMs, &e), HalStatus::kOk);       // arrives during the wait
  EXPECT_EQ(e.stamp, 105 * kMs);
  clock.set(110 * kMs);
  ASSERT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 110 * kMs);
}

TEST(HalMockGpio, InjectedFailureThenRecovery) {
  ScriptedEdgeSource src;
  src.push(1);
  src.fail_next(HalStatus::kClosed);
  GpioEdge e;
  EXPECT_EQ(src.wait_edge(0, &e), HalStatus::kClosed);
  EXPECT_STRNE(src.last_error(), "");
  EXPECT_EQ(src.pending(), 1);  // the edge is still there
  EXPECT_EQ(src.wait_edge(0, &e), HalStatus::kOk);
}

TEST(HalMockGpio, OutputRecordsLevelsWithClockStamps) {
  rtfuse::hal::mock::SimClock clock;
  RecordingGpioOutput out(3, &clock);
  EXPECT_FALSE(out.level());
  clock.set(1 * kMs);
  ASSERT_EQ(out.set(true), HalStatus::kOk);
  clock.set(2 * kMs);
  ASSERT_EQ(out.set(false), HalStatus::kOk);
  EXPECT_FALSE(out.level());
  ASSERT_EQ(out.record_count(), 2);
  EXPECT_TRUE(out.record(0).high);
  EXPECT_EQ(out.record(0).stamp, 1 * kMs);
  EXPECT_FALSE(out.record(1).high);
  EXPECT_EQ(out.record(1).stamp, 2 * kMs);
  // The log keeps the most recent ones.
  for (int i = 0; i < 4; ++i) ASSERT_EQ(out.set(i % 2 == 0), HalStatus::kOk);
  EXPECT_EQ(out.record_count(), 3);
  EXPECT_EQ(out.total_sets(), 6);
  EXPECT_FALSE(out.record(2).high);
  EXPECT_TRUE(out.record(1).high);
}

TEST(HalMockGpio, FailedSetKeepsTheLevel) {
  RecordingGpioOutput out;
  ASSERT_EQ(out.set(true), HalStatus::kOk);
  out.fail_next(HalStatus::kIoError, 2);
  EXPECT_EQ(out.set(false), HalStatus::kIoError);
  EXPECT_EQ(out.set(false), HalStatus::kIoError);
  EXPECT_TRUE(out.level());
  EXPECT_EQ(out.record_count(), 1);
  EXPECT_EQ(out.set(false), HalStatus::kOk);
  EXPECT_FALSE(out.level());
  EXPECT_EQ(out.record(1).stamp, 0);  // no clock: unstamped
}

TEST(HalMockGpio, SteadyStateDoesNotAllocate) {
  ScriptedEdgeSource src(8);
  RecordingGpioOutput out(8);
  GpioEdge e;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    src.push(i * kMs);
    (void)src.wait_edge(0, &e);
    (void)out.set(i % 2 == 0);
  }
  EXPECT_EQ(scope.count(), 0U);
}

}  // namespace mock_gpio_test
