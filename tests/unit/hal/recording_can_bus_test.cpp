#include "hal/recording_can_bus.hpp"

#include <gtest/gtest.h>

#include "hal/mock/mock_can_bus.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace recording_can_bus_test {

using rtfuse::SpscRing;
using rtfuse::TimeNs;
using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::HalStatus;
using rtfuse::hal::kBusEventMaxFrames;
using rtfuse::hal::RecordingCanBus;
using rtfuse::hal::mock::MockCanBus;
using rtfuse::hal::mock::SimClock;

CanFrame frame(std::uint32_t id, std::uint8_t dlc, std::uint8_t first = 0) {
  CanFrame f;
  f.id = id;
  f.dlc = dlc;
  for (int i = 0; i < dlc; ++i) f.data[i] = static_cast<std::uint8_t>(first + i);
  return f;
}

struct Rig {
  SimClock clock{1'000'000};
  MockCanBus bus{{}, &clock};
  SpscRing<BusEvent> ring{64};
  RecordingCanBus rec{bus, ring, 3, &clock};

  BusEvent pop() {
    BusEvent ev;
    EXPECT_TRUE(ring.try_pop(ev));
    return ev;
  }
};

TEST(HalRecordingCanBus, SendIsForwardedAndRecordedWithItsResult) {
  Rig r;
  const CanFrame sync = frame(0x080, 0);
  const CanFrame nmt = frame(0x000, 2, 0x01);
  r.clock.set(5'000'000);
  ASSERT_EQ(r.rec.send(sync), HalStatus::kOk);
  r.bus.fail_next_send(HalStatus::kBusError);
  r.clock.set(6'000'000);
  EXPECT_EQ(r.rec.send(nmt), HalStatus::kBusError);

  // The inner bus really got the first frame and not the failed one.
  ASSERT_EQ(r.bus.sent_count(), 1);
  EXPECT_EQ(r.bus.sent(0).id, 0x080u);

  ASSERT_EQ(r.ring.size(), 2u);
  const BusEvent a = r.pop();
  EXPECT_EQ(a.kind, BusEventKind::kCanSend);
  EXPECT_EQ(a.device, 3);
  EXPECT_EQ(a.time_ns, 5'000'000);
  EXPECT_EQ(a.status, HalStatus::kOk);
  EXPECT_EQ(a.bus_state, CanBusState::kErrorActive);
  EXPECT_EQ(a.count, 1);
  EXPECT_EQ(a.frames[0].id, 0x080u);
  EXPECT_EQ(a.frames[0].dlc, 0);
  const BusEvent b = r.pop();
  EXPECT_EQ(b.time_ns, 6'000'000);
  EXPECT_EQ(b.status, HalStatus::kBusError);
  EXPECT_EQ(b.frames[0].id, 0x000u);
  EXPECT_EQ(b.frames[0].dlc, 2);
  EXPECT_EQ(b.frames[0].data[0], 0x01);
  EXPECT_EQ(b.frames[0].data[1], 0x02);
  EXPECT_EQ(b.lost_before, 0u);
}

TEST(HalRecordingCanBus, ReceiveRecordsExactlyTheFramesTheCallerGot) {
  Rig r;
  r.clock.set(2'000'000);
  r.bus.inject(frame(0x181, 4, 0x10));
  r.clock.set(2'500'000);
  r.bus.inject(frame(0x701, 1, 0x05));
  r.bus.set_state(CanBusState::kErrorPassive);
  r.clock.set(3'000'000);

  CanFrame out[8];
  HalStatus st = HalStatus::kIoError;
  ASSERT_EQ(r.rec.receive(out, 8, 0, &st), 2);
  EXPECT_EQ(st, HalStatus::kOk);
  const BusEvent ev = r.pop();
  EXPECT_EQ(ev.kind, BusEventKind::kCanReceive);
  EXPECT_EQ(ev.time_ns, 3'000'000);
  EXPECT_EQ(ev.length, 8);
  EXPECT_EQ(ev.timeout_ns, 0);
  EXPECT_EQ(ev.count, 2);
  EXPECT_EQ(ev.bus_state, CanBusState::kErrorPassive);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(ev.frames[i].id, out[i].id);
    EXPECT_EQ(ev.frames[i].stamp, out[i].stamp);
    EXPECT_EQ(ev.frames[i].dlc, out[i].dlc);
  }
  EXPECT_EQ(ev.frames[0].stamp, 2'000'000);
  EXPECT_EQ(ev.frames[1].stamp, 2'500'000);
  EXPECT_EQ(ev.frames[0].data[3], 0x13);
  EXPECT_EQ(ev.frames[2].id, 0u) << "unused slots stay zero";

  // Nothing queued: the status is recorded with no frames.
  EXPECT_EQ(r.rec.receive(out, 8, 1000, &st), 0);
  EXPECT_EQ(st, HalStatus::kTimeout);
  const BusEvent empty = r.pop();
  EXPECT_EQ(empty.status, HalStatus::kTimeout);
  EXPECT_EQ(empty.timeout_ns, 1000);
  EXPECT_EQ(empty.count, 0);
}

TEST(HalRecordingCanBus, ReceiveIsCappedAtWhatOneEventHolds) {
  Rig r;
  for (int i = 0; i < 20; ++i) r.bus.inject(frame(0x100 + static_cast<std::uint32_t>(i), 1));
  CanFrame out[32];
  HalStatus st;
  EXPECT_EQ(r.rec.receive(out, 32, 0, &st), kBusEventMaxFrames);
  EXPECT_EQ(r.bus.pending(), 20 - kBusEventMaxFrames);
  const BusEvent ev = r.pop();
  EXPECT_EQ(ev.length, kBusEventMaxFrames);
  EXPECT_EQ(ev.count, kBusEventMaxFrames);
  EXPECT_EQ(ev.frames[15].id, 0x10Fu);
  EXPECT_EQ(r.rec.receive(out, 32, 0, &st), 4);
  EXPECT_EQ(r.pop().frames[0].id, 0x110u);
}

TEST(HalRecordingCanBus, FullRingLosesEventsCountsThemAndMarksTheNextOne) {
  SpscRing<BusEvent> ring(2);
  MockCanBus bus;
  RecordingCanBus rec(bus, ring, 0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(rec.send(frame(0x080, 0)), HalStatus::kOk);
  EXPECT_EQ(bus.total_sent(), 5) << "a full ring never stops the bus call";
  EXPECT_EQ(rec.overflows(), 3);
  BusEvent ev;
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.lost_before, 0u);
  ASSERT_TRUE(ring.try_pop(ev));
  rec.send(frame(0x081, 0));
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.frames[0].id, 0x081u);
  EXPECT_EQ(ev.lost_before, 3u) << "the log says where the hole is";
  rec.send(frame(0x082, 0));
  ASSERT_TRUE(ring.try_pop(ev));
  EXPECT_EQ(ev.lost_before, 0u);
}

TEST(HalRecordingCanBus, ForwardsStateAndLastError) {
  Rig r;
  r.bus.set_state(CanBusState::kBusOff);
  EXPECT_EQ(r.rec.state(), CanBusState::kBusOff);
  EXPECT_EQ(r.rec.send(frame(0x080, 0)), HalStatus::kBusError);
  EXPECT_STREQ(r.rec.last_error(), r.bus.last_error());
  EXPECT_EQ(r.pop().bus_state, CanBusState::kBusOff);
}

TEST(HalRecordingCanBus, CallsDoNotAllocate) {
  Rig r;
  CanFrame out[16];
  HalStatus st;
  r.rec.send(frame(0x080, 0));  // warm-up
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 20; ++i) {
    r.bus.inject(frame(0x181, 8));
    r.rec.send(frame(0x080, 0));
    r.rec.receive(out, 16, 0, &st);
    BusEvent ev;
    while (r.ring.try_pop(ev)) {
    }
  }
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace recording_can_bus_test
