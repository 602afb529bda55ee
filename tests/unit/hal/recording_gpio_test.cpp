#include "hal/recording_gpio.hpp"

#include <gtest/gtest.h>

#include "hal/mock/scripted_gpio.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace recording_gpio_test {

using rtfuse::SpscRing;
using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::GpioEdge;
using rtfuse::hal::HalStatus;
using rtfuse::hal::RecordingEdgeSource;
using rtfuse::hal::RecordingOutputLine;
using rtfuse::hal::mock::RecordingGpioOutput;
using rtfuse::hal::mock::ScriptedEdgeSource;
using rtfuse::hal::mock::SimClock;

TEST(HalRecordingGpio, EdgesAreRecordedWithTheirKernelStamps) {
  SimClock clock(100);
  ScriptedEdgeSource src;
  src.push(1'000, true);
  src.push(2'000, false);
  SpscRing<BusEvent> ring(16);
  RecordingEdgeSource rec(src, ring, 2, &clock);

  GpioEdge e;
  ASSERT_EQ(rec.wait_edge(5'000'000, &e), HalStatus::kOk);
  ASSERT_EQ(rec.wait_edge(5'000'000, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 2'000);
  EXPECT_EQ(rec.wait_edge(0, &e), HalStatus::kTimeout);

  BusEvent ev;
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.kind, BusEventKind::kGpioWaitEdge);
  EXPECT_EQ(ev.device, 2);
  EXPECT_EQ(ev.time_ns, 100);
  EXPECT_EQ(ev.timeout_ns, 5'000'000);
  EXPECT_EQ(ev.edge_stamp, 1'000);
  EXPECT_EQ(ev.level, 1);
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.edge_stamp, 2'000);
  EXPECT_EQ(ev.level, 0);
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.status, HalStatus::kTimeout);
  EXPECT_EQ(ev.timeout_ns, 0);
  EXPECT_EQ(ev.edge_stamp, 0) << "no edge, no stamp";
}

TEST(HalRecordingGpio, OutputLevelsAndFailuresAreRecorded) {
  RecordingGpioOutput line;  // the mock output
  SpscRing<BusEvent> ring(16);
  RecordingOutputLine rec(line, ring, 4);
  ASSERT_EQ(rec.set(true), HalStatus::kOk);
  line.fail_next(HalStatus::kIoError);
  EXPECT_EQ(rec.set(false), HalStatus::kIoError);
  EXPECT_TRUE(line.level()) << "the failed set did not reach the line";
  BusEvent ev;
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.kind, BusEventKind::kGpioSet);
  EXPECT_EQ(ev.level, 1);
  EXPECT_EQ(ev.status, HalStatus::kOk);
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.level, 0);
  EXPECT_EQ(ev.status, HalStatus::kIoError);
  EXPECT_STREQ(rec.last_error(), line.last_error());
}

TEST(HalRecordingGpio, OverflowIsCountedAndCallsDoNotAllocate) {
  ScriptedEdgeSource src(64);
  for (int i = 0; i < 10; ++i) src.push(i * 1000);
  RecordingGpioOutput line;
  SpscRing<BusEvent> ring(3);
  RecordingEdgeSource edges(src, ring, 0);
  RecordingOutputLine out(line, ring, 1);
  GpioEdge e;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 10; ++i) {
    edges.wait_edge(0, &e);
    out.set((i & 1) != 0);
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(src.delivered(), 10);
  EXPECT_EQ(edges.overflows() + out.overflows(), 17);
}

}  // namespace recording_gpio_test
