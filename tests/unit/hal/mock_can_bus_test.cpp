#include "hal/mock/mock_can_bus.hpp"

#include <gtest/gtest.h>

#include "hal/mock/sim_clock.hpp"

#include "support/alloc_counter.hpp"

namespace mock_can_bus_test {

using rtfuse::TimeNs;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::HalStatus;
using rtfuse::hal::mock::CanNode;
using rtfuse::hal::mock::CanWire;
using rtfuse::hal::mock::MockCanBus;
using rtfuse::hal::mock::MockCanBusCapacity;

constexpr TimeNs kMs = 1'000'000;

CanFrame frame(std::uint32_t id, std::uint8_t b0 = 0, std::uint8_t dlc = 1) {
  CanFrame f;
  f.id = id;
  f.dlc = dlc;
  f.data[0] = b0;
  return f;
}

// Answers every frame with id+1 and, separately, emits a tick frame every
// `period` on its own schedule, like a heartbeat producer.
class EchoNode final : public CanNode {
 public:
  explicit EchoNode(TimeNs period = 0) : period_(period) {}
  int frames_seen = 0;
  int advances = 0;
  CanFrame last{};
  void on_frame(const CanFrame& f, TimeNs now, CanWire& wire) noexcept override {
    ++frames_seen;
    last = f;
    wire.transmit(frame(f.id + 1, f.data[0]), now);
  }
  void advance(TimeNs now, CanWire& wire) noexcept override {
    ++advances;
    if (period_ <= 0) return;
    if (next_ == 0) next_ = now + period_;
    while (next_ <= now) {
      wire.transmit(frame(0x7FF, 0xAA), next_);
      next_ += period_;
    }
  }

 private:
  TimeNs period_;
  TimeNs next_ = 0;
};

TEST(HalMockCanBus, InjectedFramesComeOutInOrderStampedWithBusTime) {
  MockCanBus bus;
  bus.set_time(5 * kMs);
  ASSERT_TRUE(bus.inject(frame(0x181, 1)));
  bus.set_time(7 * kMs);
  ASSERT_TRUE(bus.inject(frame(0x182, 2)));
  ASSERT_TRUE(bus.inject(frame(0x183, 3)));
  EXPECT_EQ(bus.pending(), 3);

  CanFrame out[2];
  HalStatus st = HalStatus::kIoError;
  ASSERT_EQ(bus.receive(out, 2, 0, &st), 2);
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(out[0].id, 0x181U);
  EXPECT_EQ(out[0].stamp, 5 * kMs);
  EXPECT_EQ(out[1].id, 0x182U);
  EXPECT_EQ(out[1].stamp, 7 * kMs);
  ASSERT_EQ(bus.receive(out, 2, 0, &st), 1);  // the rest, not more
  EXPECT_EQ(out[0].id, 0x183U);
  EXPECT_EQ(out[0].data[0], 3);
  EXPECT_EQ(bus.receive(out, 2, 0, &st), 0);
  EXPECT_EQ(st, HalStatus::kWouldBlock);
}

TEST(HalMockCanBus, EmptyReceiveWithTimeoutMovesManualTimeAndTimesOut) {
  MockCanBus bus;
  bus.set_time(100 * kMs);
  CanFrame out[4];
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(bus.receive(out, 4, 20 * kMs, &st), 0);
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(bus.now(), 120 * kMs);
}

TEST(HalMockCanBus, TimeoutReceiveDeliversWhatANodeEmitsWithinTheWait) {
  MockCanBus bus;
  EchoNode node(10 * kMs);
  ASSERT_TRUE(bus.attach(node));  // schedule starts at t=0
  CanFrame out[4];
  HalStatus st = HalStatus::kOk;
  // Due at 10 ms, inside a 15 ms wait from 0: time stops at the answer.
  ASSERT_EQ(bus.receive(out, 4, 15 * kMs, &st), 1);
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(out[0].id, 0x7FFU);
  EXPECT_EQ(out[0].stamp, 10 * kMs);
  EXPECT_EQ(bus.now(), 10 * kMs);
  // Next one due at 20 ms, beyond a 5 ms wait: nothing, time at 15 ms.
  EXPECT_EQ(bus.receive(out, 4, 5 * kMs, &st), 0);
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(bus.now(), 15 * kMs);
}

TEST(HalMockCanBus, WithAClockReceiveNeverMovesTimeAndNodesFollowTheClock) {
  rtfuse::hal::mock::SimClock clock(1000 * kMs);
  MockCanBus bus({}, &clock);
  EchoNode node(10 * kMs);
  ASSERT_TRUE(bus.attach(node));
  CanFrame out[4];
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(bus.receive(out, 4, 50 * kMs, &st), 0);
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(bus.now(), 1000 * kMs);
  bus.set_time(5);  // ignored while the clock rules
  EXPECT_EQ(bus.now(), 1000 * kMs);
  clock.set(1025 * kMs);
  ASSERT_EQ(bus.receive(out, 4, 0, &st), 2);
  EXPECT_EQ(out[0].stamp, 1010 * kMs);
  EXPECT_EQ(out[1].stamp, 1020 * kMs);
  ASSERT_EQ(bus.send(frame(0x10)), HalStatus::kOk);
  EXPECT_EQ(bus.sent(0).stamp, 1025 * kMs);
}

TEST(HalMockCanBus, SentFramesAreLoggedAndShownToEveryNode) {
  MockCanBus bus;
  EchoNode a;
  EchoNode b;
  ASSERT_TRUE(bus.attach(a));
  ASSERT_TRUE(bus.attach(b));
  EXPECT_FALSE(bus.attach(a));  // once only
  EXPECT_EQ(bus.node_count(), 2);
  bus.set_time(3 * kMs);
  CanFrame f = frame(0x080, 0, 0);
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  ASSERT_EQ(bus.sent_count(), 1);
  EXPECT_EQ(bus.sent(0).id, 0x080U);
  EXPECT_EQ(bus.sent(0).stamp, 3 * kMs);
  EXPECT_EQ(a.frames_seen, 1);
  EXPECT_EQ(b.frames_seen, 1);
  // Both answers queued, in attach order; the host's own frame is not echoed.
  CanFrame out[4];
  HalStatus st;
  ASSERT_EQ(bus.receive(out, 4, 0, &st), 2);
  EXPECT_EQ(out[0].id, 0x081U);
  EXPECT_EQ(out[1].id, 0x081U);
  bus.detach(a);
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  EXPECT_EQ(a.frames_seen, 1);
  EXPECT_EQ(b.frames_seen, 2);
  bus.clear_sent();
  EXPECT_EQ(bus.sent_count(), 0);
  EXPECT_EQ(bus.total_sent(), 2);
}

TEST(HalMockCanBus, SendLogKeepsTheMostRecentFrames) {
  MockCanBusCapacity cap;
  cap.sent_frames = 3;
  MockCanBus bus(cap);
  for (std::uint32_t id = 1; id <= 5; ++id) ASSERT_EQ(bus.send(frame(id)), HalStatus::kOk);
  ASSERT_EQ(bus.sent_count(), 3);
  EXPECT_EQ(bus.sent(0).id, 3U);
  EXPECT_EQ(bus.sent(2).id, 5U);
  EXPECT_EQ(bus.sent(3).id, 0U);  // out of range: an empty frame, not a crash
  EXPECT_EQ(bus.total_sent(), 5);
}

TEST(HalMockCanBus, InjectedSendFailuresNeverReachTheWire) {
  MockCanBus bus;
  EchoNode node;
  ASSERT_TRUE(bus.attach(node));
  bus.fail_next_send(HalStatus::kIoError, 2);
  EXPECT_EQ(bus.send(frame(0x1)), HalStatus::kIoError);
  EXPECT_STRNE(bus.last_error(), "");
  EXPECT_EQ(bus.send(frame(0x2)), HalStatus::kIoError);
  EXPECT_EQ(bus.send(frame(0x3)), HalStatus::kOk);
  ASSERT_EQ(bus.sent_count(), 1);
  EXPECT_EQ(bus.sent(0).id, 0x3U);
  EXPECT_EQ(node.frames_seen, 1);
}

TEST(HalMockCanBus, BusOffRefusesToSendUntilRecovered) {
  MockCanBus bus;
  EchoNode node;
  ASSERT_TRUE(bus.attach(node));
  EXPECT_EQ(bus.state(), CanBusState::kErrorActive);
  bus.set_state(CanBusState::kBusOff);
  EXPECT_EQ(bus.state(), CanBusState::kBusOff);
  EXPECT_EQ(bus.send(frame(0x80)), HalStatus::kBusError);
  EXPECT_EQ(node.frames_seen, 0);
  EXPECT_EQ(bus.sent_count(), 0);
  bus.set_state(CanBusState::kErrorActive);
  EXPECT_EQ(bus.send(frame(0x80)), HalStatus::kOk);
  EXPECT_EQ(node.frames_seen, 1);
}

TEST(HalMockCanBus, RejectsAClassicFrameLongerThanEightBytes) {
  MockCanBus bus;
  EXPECT_EQ(bus.send(frame(0x80, 0, 9)), HalStatus::kIoError);
  EXPECT_EQ(bus.sent_count(), 0);
}

TEST(HalMockCanBus, FullReceiveQueueDropsAndCounts) {
  MockCanBusCapacity cap;
  cap.rx_frames = 2;
  MockCanBus bus(cap);
  EXPECT_TRUE(bus.inject(frame(1)));
  EXPECT_TRUE(bus.inject(frame(2)));
  EXPECT_FALSE(bus.inject(frame(3)));
  EXPECT_EQ(bus.rx_dropped(), 1);
  CanFrame out[4];
  HalStatus st;
  ASSERT_EQ(bus.receive(out, 4, 0, &st), 2);
  EXPECT_EQ(out[1].id, 2U);
  EXPECT_TRUE(bus.inject(frame(4)));  // room again after the drain (ring wraps)
  ASSERT_EQ(bus.receive(out, 4, 0, &st), 1);
  EXPECT_EQ(out[0].id, 4U);
}

TEST(HalMockCanBus, NodeTableHasAFixedCapacity) {
  MockCanBusCapacity cap;
  cap.nodes = 1;
  MockCanBus bus(cap);
  EchoNode a;
  EchoNode b;
  EXPECT_TRUE(bus.attach(a));
  EXPECT_EQ(a.advances, 1);  // powered up when plugged in
  EXPECT_FALSE(bus.attach(b));
  bus.detach(a);
  EXPECT_TRUE(bus.attach(b));
}

TEST(HalMockCanBus, BadReceiveArgumentsReturnZero) {
  MockCanBus bus;
  ASSERT_TRUE(bus.inject(frame(1)));
  HalStatus st = HalStatus::kIoError;
  EXPECT_EQ(bus.receive(nullptr, 4, 0, &st), 0);
  CanFrame out[1];
  EXPECT_EQ(bus.receive(out, 0, 0, &st), 0);
  EXPECT_EQ(bus.receive(out, 1, 0, nullptr), 1);  // status is optional
}

TEST(HalMockCanBus, SteadyStateDoesNotAllocate) {
  MockCanBus bus;
  EchoNode node(1 * kMs);
  ASSERT_TRUE(bus.attach(node));
  CanFrame out[16];
  HalStatus st;
  rtfuse::test::AllocScope scope;
  for (int i = 1; i <= 1000; ++i) {
    bus.set_time(i * kMs);
    (void)bus.send(frame(0x080, 0, 0));
    (void)bus.receive(out, 16, 0, &st);
    (void)bus.receive(out, 16, 2 * kMs, &st);
  }
  EXPECT_EQ(scope.count(), 0U);
}

}  // namespace mock_can_bus_test
