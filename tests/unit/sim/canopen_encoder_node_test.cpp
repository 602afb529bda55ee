#include "sim/devices/canopen_encoder_node.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "support/alloc_counter.hpp"

namespace canopen_encoder_node_test {

using rtfuse::TimeNs;
using rtfuse::hal::CanFrame;
using rtfuse::hal::HalStatus;
using rtfuse::sim::CanopenEncoderConfig;
using rtfuse::sim::CanopenEncoderNode;
using rtfuse::hal::mock::MockCanBus;
using NmtState = rtfuse::sim::canopen::NmtState;

constexpr TimeNs kMs = 1'000'000;

CanFrame nmt(std::uint8_t cs, std::uint8_t node) {
  CanFrame f;
  f.id = 0x000;
  f.dlc = 2;
  f.data[0] = cs;
  f.data[1] = node;
  return f;
}

CanFrame sync_frame() {
  CanFrame f;
  f.id = 0x080;
  f.dlc = 0;
  return f;
}

std::vector<CanFrame> drain(MockCanBus& bus) {
  std::vector<CanFrame> all;
  CanFrame out[32];
  HalStatus st;
  int n;
  while ((n = bus.receive(out, 32, 0, &st)) > 0) all.insert(all.end(), out, out + n);
  return all;
}

CanopenEncoderConfig config(std::uint8_t id, TimeNs hb = 100 * kMs) {
  CanopenEncoderConfig c;
  c.node_id = id;
  c.heartbeat_period_ns = hb;
  return c;
}

TEST(HalMockCanopen, SendsBootUpWhenPluggedInAndEntersPreOperational) {
  MockCanBus bus;
  bus.set_time(50 * kMs);
  CanopenEncoderNode node(config(5));
  EXPECT_FALSE(node.booted());
  ASSERT_TRUE(bus.attach(node));
  auto frames = drain(bus);
  ASSERT_EQ(frames.size(), 1U);
  EXPECT_EQ(frames[0].id, 0x705U);
  EXPECT_EQ(frames[0].dlc, 1);
  EXPECT_EQ(frames[0].data[0], 0x00);
  EXPECT_EQ(frames[0].stamp, 50 * kMs);
  EXPECT_EQ(node.nmt_state(), NmtState::kPreOperational);
  EXPECT_EQ(node.boot_count(), 1);
}

TEST(HalMockCanopen, HeartbeatEveryPeriodCarriesTheNmtState) {
  MockCanBus bus;
  CanopenEncoderNode node(config(3));
  ASSERT_TRUE(bus.attach(node));
  drain(bus);
  bus.set_time(99 * kMs);
  EXPECT_TRUE(drain(bus).empty());
  bus.set_time(100 * kMs);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].id, 0x703U);
  EXPECT_EQ(f[0].dlc, 1);
  EXPECT_EQ(f[0].data[0], 0x7F);  // pre-operational
  EXPECT_EQ(f[0].stamp, 100 * kMs);

  ASSERT_EQ(bus.send(nmt(0x01, 3)), HalStatus::kOk);
  bus.set_time(200 * kMs);
  f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].data[0], 0x05);  // operational

  ASSERT_EQ(bus.send(nmt(0x02, 3)), HalStatus::kOk);
  // A late look at the clock still yields every beat, stamped when it was due.
  bus.set_time(450 * kMs);
  f = drain(bus);
  ASSERT_EQ(f.size(), 2U);
  EXPECT_EQ(f[0].data[0], 0x04);  // stopped: heartbeat keeps running
  EXPECT_EQ(f[0].stamp, 300 * kMs);
  EXPECT_EQ(f[1].stamp, 400 * kMs);
}

TEST(HalMockCanopen, ZeroHeartbeatPeriodMeansNoHeartbeat) {
  MockCanBus bus;
  CanopenEncoderNode node(config(3, 0));
  ASSERT_TRUE(bus.attach(node));
  EXPECT_EQ(drain(bus).size(), 1U);  // boot-up only
  bus.set_time(10'000 * kMs);
  EXPECT_TRUE(drain(bus).empty());
}

TEST(HalMockCanopen, NmtStateMachine) {
  MockCanBus bus;
  CanopenEncoderNode node(config(7, 0));
  ASSERT_TRUE(bus.attach(node));
  drain(bus);
  struct Step {
    std::uint8_t cs;
    NmtState expect;
  };
  const Step steps[] = {
      {0x01, NmtState::kOperational},    {0x80, NmtState::kPreOperational}, {0x02, NmtState::kStopped},
      {0x80, NmtState::kPreOperational}, {0x02, NmtState::kStopped},        {0x01, NmtState::kOperational},
      {0x02, NmtState::kStopped},        {0x33, NmtState::kStopped},  // unknown command: ignored
  };
  for (const Step& s : steps) {
    ASSERT_EQ(bus.send(nmt(s.cs, 7)), HalStatus::kOk);
    EXPECT_EQ(node.nmt_state(), s.expect) << "command 0x" << std::hex << int(s.cs);
  }
  EXPECT_TRUE(drain(bus).empty());  // state changes alone send nothing
}

TEST(HalMockCanopen, NmtForAnotherNodeIsIgnoredAndNodeZeroReachesAll) {
  MockCanBus bus;
  CanopenEncoderNode a(config(1, 0));
  CanopenEncoderNode b(config(2, 0));
  ASSERT_TRUE(bus.attach(a));
  ASSERT_TRUE(bus.attach(b));
  ASSERT_EQ(bus.send(nmt(0x01, 2)), HalStatus::kOk);
  EXPECT_EQ(a.nmt_state(), NmtState::kPreOperational);
  EXPECT_EQ(b.nmt_state(), NmtState::kOperational);
  ASSERT_EQ(bus.send(nmt(0x01, 0)), HalStatus::kOk);
  EXPECT_EQ(a.nmt_state(), NmtState::kOperational);
  EXPECT_EQ(b.nmt_state(), NmtState::kOperational);
  ASSERT_EQ(bus.send(nmt(0x02, 0)), HalStatus::kOk);
  EXPECT_EQ(a.nmt_state(), NmtState::kStopped);
  EXPECT_EQ(b.nmt_state(), NmtState::kStopped);
}

TEST(HalMockCanopen, NmtWithWrongLengthOrFormatIsIgnored) {
  MockCanBus bus;
  CanopenEncoderNode node(config(1, 0));
  ASSERT_TRUE(bus.attach(node));
  CanFrame f = nmt(0x01, 1);
  f.dlc = 3;
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  f.dlc = 1;
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  f = nmt(0x01, 1);
  f.extended = true;  // 29-bit id 0 is not the NMT object
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  f = nmt(0x01, 1);
  f.rtr = true;
  ASSERT_EQ(bus.send(f), HalStatus::kOk);
  EXPECT_EQ(node.nmt_state(), NmtState::kPreOperational);
}

TEST(HalMockCanopen, ResetNodeAndResetCommunicationBootAgain) {
  for (std::uint8_t cs : {std::uint8_t{0x81}, std::uint8_t{0x82}}) {
    MockCanBus bus;
    CanopenEncoderNode node(config(9));
    ASSERT_TRUE(bus.attach(node));
    ASSERT_EQ(bus.send(nmt(0x01, 9)), HalStatus::kOk);
    drain(bus);
    bus.set_time(130 * kMs);
    drain(bus);  // the 100 ms beat
    ASSERT_EQ(bus.send(nmt(cs, 0)), HalStatus::kOk);
    auto f = drain(bus);
    ASSERT_EQ(f.size(), 1U) << std::hex << int(cs);
    EXPECT_EQ(f[0].id, 0x709U);
    EXPECT_EQ(f[0].data[0], 0x00);
    EXPECT_EQ(f[0].stamp, 130 * kMs);
    EXPECT_EQ(node.nmt_state(), NmtState::kPreOperational);
    EXPECT_EQ(node.boot_count(), 2);
    // The heartbeat timer restarts at the boot-up.
    bus.set_time(229 * kMs);
    EXPECT_TRUE(drain(bus).empty());
    bus.set_time(230 * kMs);
    f = drain(bus);
    ASSERT_EQ(f.size(), 1U);
    EXPECT_EQ(f[0].data[0], 0x7F);
  }
}

TEST(HalMockCanopen, TpdoOnSyncOnlyWhenOperational) {
  MockCanBus bus;
  CanopenEncoderConfig c = config(4, 0);
  c.initial_position = 0x01020304;
  CanopenEncoderNode node(c);
  ASSERT_TRUE(bus.attach(node));
  drain(bus);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  EXPECT_TRUE(drain(bus).empty());  // pre-operational: no PDO

  ASSERT_EQ(bus.send(nmt(0x01, 4)), HalStatus::kOk);
  bus.set_time(1 * kMs);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].id, 0x184U);
  EXPECT_EQ(f[0].dlc, 4);
  EXPECT_EQ(f[0].data[0], 0x04);  // little-endian
  EXPECT_EQ(f[0].data[1], 0x03);
  EXPECT_EQ(f[0].data[2], 0x02);
  EXPECT_EQ(f[0].data[3], 0x01);
  EXPECT_EQ(f[0].stamp, 1 * kMs);
  EXPECT_EQ(node.tpdo_count(), 1);

  ASSERT_EQ(bus.send(nmt(0x02, 4)), HalStatus::kOk);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  EXPECT_TRUE(drain(bus).empty());  // stopped: no PDO
  ASSERT_EQ(bus.send(nmt(0x80, 4)), HalStatus::kOk);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  EXPECT_TRUE(drain(bus).empty());
  EXPECT_EQ(node.tpdo_count(), 1);
}

struct LayoutCase {
  int width;
  bool is_signed;
  int offset;
  std::int64_t counts;          // unwrapped position
  std::uint8_t bytes[4];        // expected wire bytes (width of them)
  std::int64_t value;           // position_value()
};

class HalMockCanopenLayout : public ::testing::TestWithParam<LayoutCase> {};

TEST_P(HalMockCanopenLayout, TpdoBytesMatchWidthSignednessAndWrap) {
  const LayoutCase& p = GetParam();
  MockCanBus bus;
  CanopenEncoderConfig c = config(2, 0);
  c.position_width = static_cast<std::uint8_t>(p.width);
  c.position_signed = p.is_signed;
  c.position_offset = static_cast<std::uint8_t>(p.offset);
  c.initial_position = p.counts;
  CanopenEncoderNode node(c);
  ASSERT_TRUE(node.valid());
  ASSERT_TRUE(bus.attach(node));
  ASSERT_EQ(bus.send(nmt(0x01, 2)), HalStatus::kOk);
  drain(bus);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].dlc, p.offset + p.width);
  for (int i = 0; i < p.offset; ++i) EXPECT_EQ(f[0].data[i], 0) << "byte " << i;
  for (int i = 0; i < p.width; ++i) EXPECT_EQ(f[0].data[p.offset + i], p.bytes[i]) << "byte " << i;
  EXPECT_EQ(node.position_value(0), p.value);
}

INSTANTIATE_TEST_SUITE_P(
    Widths, HalMockCanopenLayout,
    ::testing::Values(
        LayoutCase{1, false, 0, 0xAB, {0xAB}, 0xAB},
        LayoutCase{1, false, 0, 256 + 5, {0x05}, 5},                 // wraps at 8 bits
        LayoutCase{1, true, 0, 0x80, {0x80}, -128},
        LayoutCase{1, true, 2, -1, {0xFF}, -1},
        LayoutCase{2, false, 0, 65535 + 3, {0x02, 0x00}, 2},         // wraps at 16 bits
        LayoutCase{2, true, 0, 32767 + 1, {0x00, 0x80}, -32768},
        LayoutCase{2, true, 1, -2, {0xFE, 0xFF}, -2},
        LayoutCase{3, false, 0, 0x123456, {0x56, 0x34, 0x12}, 0x123456},
        LayoutCase{3, true, 0, -0x800000, {0x00, 0x00, 0x80}, -0x800000},
        LayoutCase{3, false, 4, (std::int64_t{1} << 24) + 7, {0x07, 0x00, 0x00}, 7},
        LayoutCase{4, false, 0, -1, {0xFF, 0xFF, 0xFF, 0xFF}, 0xFFFFFFFF},
        LayoutCase{4, true, 0, -1, {0xFF, 0xFF, 0xFF, 0xFF}, -1},
        LayoutCase{4, true, 4, 0x7FFFFFFF + std::int64_t{1}, {0x00, 0x00, 0x00, 0x80}, -0x80000000LL},
        LayoutCase{4, false, 0, (std::int64_t{1} << 32) + 0x10, {0x10, 0x00, 0x00, 0x00}, 0x10}));

TEST(HalMockCanopen, InvalidLayoutIsClampedAndReported) {
  CanopenEncoderConfig c = config(1);
  c.position_width = 5;
  c.position_offset = 6;
  CanopenEncoderNode node(c);
  EXPECT_FALSE(node.valid());
  EXPECT_EQ(node.config().position_width, 4);
  EXPECT_EQ(node.config().position_offset, 4);
  EXPECT_EQ(node.config().tpdo_dlc, 8);
}

TEST(HalMockCanopen, PositionIntegratesSpeedAndWrapsOnTheWire) {
  MockCanBus bus;
  CanopenEncoderConfig c = config(1, 0);
  c.position_width = 2;
  c.speed_counts_per_s = 1000.0;
  c.initial_position = 65000;
  CanopenEncoderNode node(c);
  ASSERT_TRUE(bus.attach(node));  // integration starts at t=0
  ASSERT_EQ(bus.send(nmt(0x01, 1)), HalStatus::kOk);
  drain(bus);
  bus.set_time(1500 * kMs);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  // 65000 + 1500 = 66500 -> 66500 - 65536 = 964 = 0x03C4
  EXPECT_EQ(f[0].data[0], 0xC4);
  EXPECT_EQ(f[0].data[1], 0x03);
  EXPECT_EQ(node.counts_at(1500 * kMs), 66500);
  node.set_speed(-2000.0, 1500 * kMs);
  EXPECT_EQ(node.counts_at(2000 * kMs), 65500);
  EXPECT_EQ(node.counts_at(1999 * kMs), 65502);
  // Whole counts only: half a count has not been registered yet.
  EXPECT_EQ(node.counts_at(2000 * kMs + 250'000), 65499);
  node.set_position(10, 2000 * kMs);
  EXPECT_EQ(node.counts_at(2001 * kMs), 8);
}

TEST(HalMockCanopen, SilentNodeSendsAndHearsNothingThenResumesOnItsPhase) {
  MockCanBus bus;
  CanopenEncoderNode node(config(6));
  ASSERT_TRUE(bus.attach(node));
  ASSERT_EQ(bus.send(nmt(0x01, 6)), HalStatus::kOk);
  drain(bus);
  node.set_silent(true, 0);
  bus.set_time(550 * kMs);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  ASSERT_EQ(bus.send(nmt(0x02, 6)), HalStatus::kOk);  // lost: the node is off the bus
  const std::uint8_t mfr[5] = {};
  EXPECT_FALSE(node.emit_emcy(0x1000, 0x01, mfr, 550 * kMs, bus));
  EXPECT_TRUE(drain(bus).empty());
  EXPECT_EQ(node.nmt_state(), NmtState::kOperational);
  node.set_silent(false, 550 * kMs);
  bus.set_time(599 * kMs);
  EXPECT_TRUE(drain(bus).empty());  // no burst of the missed beats
  bus.set_time(600 * kMs);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].stamp, 600 * kMs);
  EXPECT_EQ(f[0].data[0], 0x05);
}

TEST(HalMockCanopen, NodeSilentFromPowerUpBootsWhenItComesBack) {
  MockCanBus bus;
  CanopenEncoderNode node(config(6));
  node.set_silent(true, 0);
  ASSERT_TRUE(bus.attach(node));
  EXPECT_TRUE(drain(bus).empty());
  node.set_silent(false, 0);
  bus.set_time(20 * kMs);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].id, 0x706U);
  EXPECT_EQ(f[0].data[0], 0x00);
}

TEST(HalMockCanopen, StuckCounterFreezesAndCountsOnAfterRelease) {
  MockCanBus bus;
  CanopenEncoderConfig c = config(1, 0);
  c.speed_counts_per_s = 100.0;
  CanopenEncoderNode node(c);
  ASSERT_TRUE(bus.attach(node));
  ASSERT_EQ(bus.send(nmt(0x01, 1)), HalStatus::kOk);
  node.set_stuck(true, 1000 * kMs);
  EXPECT_EQ(node.counts_at(1000 * kMs), 100);
  EXPECT_EQ(node.counts_at(3000 * kMs), 100);
  bus.set_time(3000 * kMs);
  drain(bus);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].data[0], 100);  // still answering, with the frozen value
  node.set_stuck(false, 3000 * kMs);
  EXPECT_EQ(node.counts_at(4000 * kMs), 200);
}

TEST(HalMockCanopen, JumpShiftsTheCounterAtOnce) {
  CanopenEncoderConfig c = config(1, 0);
  c.initial_position = 10;
  CanopenEncoderNode node(c);
  node.jump(5000);
  EXPECT_EQ(node.counts_at(0), 5010);
  node.jump(-5020);
  EXPECT_EQ(node.counts_at(0), -10);
}

TEST(HalMockCanopen, EmcyLayoutAndNotWhenStopped) {
  MockCanBus bus;
  CanopenEncoderNode node(config(0x21, 0));
  ASSERT_TRUE(bus.attach(node));
  drain(bus);
  const std::uint8_t mfr[5] = {0xA1, 0xA2, 0xA3, 0xA4, 0xA5};
  bus.set_time(7 * kMs);
  ASSERT_TRUE(node.emit_emcy(0x8130, 0x11, mfr, bus.now(), bus));
  auto f = drain(bus);
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].id, 0x0A1U);
  EXPECT_EQ(f[0].dlc, 8);
  const std::uint8_t expect[8] = {0x30, 0x81, 0x11, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(f[0].data[i], expect[i]) << "byte " << i;
  EXPECT_EQ(f[0].stamp, 7 * kMs);
  ASSERT_EQ(bus.send(nmt(0x02, 0x21)), HalStatus::kOk);
  EXPECT_FALSE(node.emit_emcy(0x8130, 0x11, mfr, bus.now(), bus));
  EXPECT_TRUE(drain(bus).empty());
}

TEST(HalMockCanopen, SteadyStatePollingDoesNotAllocate) {
  MockCanBus bus;
  CanopenEncoderConfig c = config(1, 10 * kMs);
  c.speed_counts_per_s = 5000.0;
  CanopenEncoderNode a(c);
  c.node_id = 2;
  CanopenEncoderNode b(c);
  ASSERT_TRUE(bus.attach(a));
  ASSERT_TRUE(bus.attach(b));
  ASSERT_EQ(bus.send(nmt(0x01, 0)), HalStatus::kOk);
  CanFrame out[16];
  HalStatus st;
  int tpdos = 0;
  rtfuse::test::AllocScope scope;
  for (int i = 1; i <= 1000; ++i) {
    bus.set_time(i * kMs);
    (void)bus.send(sync_frame());
    int n;
    while ((n = bus.receive(out, 16, 0, &st)) > 0) {
      for (int k = 0; k < n; ++k) tpdos += (out[k].id & 0x780) == 0x180 ? 1 : 0;
    }
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(tpdos, 2000);
}

}  // namespace canopen_encoder_node_test
