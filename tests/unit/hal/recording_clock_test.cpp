#include "hal/recording_clock.hpp"

#include <gtest/gtest.h>

#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace recording_clock_test {

using rtfuse::SpscRing;
using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::RecordingClock;
using rtfuse::hal::mock::SimClock;

TEST(HalRecordingClock, RecordsReadingsAndDeadlines) {
  SimClock sim(1'000);
  SpscRing<BusEvent> ring(16);
  RecordingClock clock(sim, ring, 5);
  EXPECT_EQ(clock.now(), 1'000);
  clock.sleep_until(4'000);
  EXPECT_EQ(sim.now(), 4'000) << "the sleep reached the inner clock";
  EXPECT_EQ(clock.now(), 4'000);

  BusEvent ev;
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.kind, BusEventKind::kClockNow);
  EXPECT_EQ(ev.device, 5);
  EXPECT_EQ(ev.clock_ns, 1'000);
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.kind, BusEventKind::kClockSleepUntil);
  EXPECT_EQ(ev.clock_ns, 4'000);
  EXPECT_EQ(ev.time_ns, 1'000) << "time of the call, before sleeping";
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.clock_ns, 4'000);
  EXPECT_FALSE(ring.try_pop(ev));
}

TEST(HalRecordingClock, OverflowIsCountedAndCallsDoNotAllocate) {
  SimClock sim(0);
  SpscRing<BusEvent> ring(8);
  RecordingClock clock(sim, ring, 0);
  rtfuse::test::AllocScope scope;
  for (int i = 1; i <= 10; ++i) {
    clock.sleep_until(i * 1000);
    EXPECT_EQ(clock.now(), i * 1000);
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(clock.overflows(), 12);
}

}  // namespace recording_clock_test
