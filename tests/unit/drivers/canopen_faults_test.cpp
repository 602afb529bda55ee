// Each encoder fault: detected, counted, the node excluded with the reason,
// and recovered without a restart. Plus malformed traffic and allocation.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "drivers/canopen/canopen_encoders.hpp"
#include "sim/devices/canopen_encoder_node.hpp"
#include "hal/mock/mock_can_bus.hpp"
#include "support/alloc_counter.hpp"

namespace canopen_faults_test {

using rtfuse::TimeNs;
using rtfuse::drivers::CanopenEncoders;
using rtfuse::drivers::CanopenEncodersConfig;
using rtfuse::drivers::EncoderHealth;
using rtfuse::drivers::EncoderSampleSet;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::HalStatus;
using rtfuse::sim::CanopenEncoderConfig;
using rtfuse::sim::CanopenEncoderNode;
using rtfuse::hal::mock::MockCanBus;
using NmtState = rtfuse::sim::canopen::NmtState;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 5 * kMs;

struct Rig {
  MockCanBus bus;
  std::vector<std::unique_ptr<CanopenEncoderNode>> nodes;
  std::unique_ptr<CanopenEncoders> enc;
  TimeNs t = 0;

  // Nodes 1..n, 32-bit, heartbeat every 100 ms, each at its speed.
  Rig(std::initializer_list<double> speeds, CanopenEncodersConfig mc = {}) {
    std::uint8_t id = 1;
    mc.node_count = 0;
    for (double s : speeds) {
      CanopenEncoderConfig c;
      c.node_id = id;
      c.speed_counts_per_s = s;
      nodes.push_back(std::make_unique<CanopenEncoderNode>(c));
      EXPECT_TRUE(bus.attach(*nodes.back()));
      mc.nodes[static_cast<std::size_t>(mc.node_count++)].node_id = id++;
    }
    std::string error;
    enc = CanopenEncoders::create(bus, mc, &error);
    EXPECT_NE(enc, nullptr) << error;
    EXPECT_TRUE(enc->start(0));
  }
  void tick() {
    t += kPeriod;
    bus.set_time(t);
    enc->poll(t);
  }
  void run_for(TimeNs d) {
    const TimeNs end = t + d;
    while (t < end) tick();
  }
  const rtfuse::drivers::EncoderReading& r(int i) const { return enc->reading(i); }
  const rtfuse::drivers::EncoderNodeStats& st(int i) const { return enc->node_stats(i); }
  CanopenEncoderNode& node(int i) { return *nodes[static_cast<std::size_t>(i)]; }
};

TEST(CanopenFaults, NodeSilentForTwoSecondsIsExcludedThenRecovers) {
  Rig rig({1000.0, 1000.0});
  rig.run_for(100 * kMs);
  ASSERT_TRUE(rig.r(0).valid);
  const std::int64_t counts0 = rig.r(0).counts;
  const std::int64_t truth0 = rig.node(0).counts_at(rig.r(0).stamp);
  const std::uint32_t segment0 = rig.r(0).segment;

  rig.node(0).set_silent(true, rig.t);
  EncoderSampleSet set;
  rig.tick();  // the answer to the SYNC sent before the silence still counts
  EXPECT_TRUE(rig.r(0).valid);
  for (int i = 1; i <= 4; ++i) {
    rig.tick();
    EXPECT_EQ(rig.r(0).health, EncoderHealth::kNoSample) << i;
    EXPECT_FALSE(rig.r(0).valid);
    EXPECT_FALSE(rig.enc->take_sample_set(&set)) << "node 1 has not answered: set incomplete";
  }
  EXPECT_STREQ(rig.enc->node_error(0), "");
  rig.tick();  // the fifth SYNC without a TPDO
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kSilent);
  EXPECT_EQ(rig.st(0).silent_events, 1);
  EXPECT_STREQ(rig.enc->node_error(0), "node 1: no TPDO for 5 SYNCs in a row");
  EXPECT_STREQ(rig.enc->node_error(1), "");
  EXPECT_STREQ(rig.enc->node_error(2), "") << "no such node";
  ASSERT_TRUE(rig.enc->take_sample_set(&set)) << "a silent node no longer holds the others back";
  EXPECT_EQ(set.valid_count, 1);
  EXPECT_FALSE(set.readings[0].valid);
  EXPECT_TRUE(set.readings[1].valid);

  rig.run_for(2000 * kMs);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kSilent);
  EXPECT_EQ(rig.st(0).silent_events, 1) << "the heartbeat timeout adds no second event";
  EXPECT_TRUE(rig.r(1).valid);

  rig.node(0).set_silent(false, rig.t);
  rig.run_for(150 * kMs);  // TPDOs on the next SYNC, heartbeat within its 100 ms period
  ASSERT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kOk);
  EXPECT_EQ(rig.st(0).recoveries, 1);
  EXPECT_STREQ(rig.enc->node_error(0), "node 1: no TPDO for 5 SYNCs in a row") << "kept after the recovery";
  EXPECT_EQ(rig.r(0).segment, segment0 + 1) << "continuity across the silence is not vouched for";
  // A 32-bit counter moved far less than half its range: the guess is right.
  EXPECT_EQ(rig.r(0).counts - counts0, rig.node(0).counts_at(rig.r(0).stamp) - truth0);
  EXPECT_GE(rig.st(0).missed_syncs, 400);
  EXPECT_EQ(rig.st(1).silent_events, 0);
}

TEST(CanopenFaults, HeartbeatTimeoutAloneMakesANodeSilent) {
  CanopenEncodersConfig mc;
  mc.tpdo_timeout_syncs = 10'000;  // only the heartbeat can tell
  Rig rig({0.0}, mc);
  rig.run_for(300 * kMs);  // last heartbeat at 300 ms
  rig.node(0).set_silent(true, rig.t);
  rig.run_for(490 * kMs);  // 790 ms: 490 ms since the last heartbeat
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kNoSample);
  rig.run_for(20 * kMs);  // 810 ms: 510 ms
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kSilent);
  EXPECT_EQ(rig.st(0).silent_events, 1);
  EXPECT_STREQ(rig.enc->node_error(0), "node 1: no heartbeat for more than 500 ms");
}

TEST(CanopenFaults, RebootedNodeIsStartedAgainRateLimited) {
  Rig rig({500.0});
  rig.run_for(500 * kMs);
  ASSERT_TRUE(rig.r(0).valid);
  CanFrame reset;
  reset.id = 0x000;
  reset.dlc = 2;
  reset.data[0] = 0x81;  // reset node: it boots again, pre-operational
  reset.data[1] = 1;
  ASSERT_EQ(rig.bus.send(reset), HalStatus::kOk);
  EXPECT_EQ(rig.node(0).nmt_state(), NmtState::kPreOperational);
  rig.tick();  // sees the boot-up, sends NMT start at once
  EXPECT_EQ(rig.node(0).nmt_state(), NmtState::kOperational);
  EXPECT_EQ(rig.st(0).nmt_starts, 2);
  EXPECT_EQ(rig.st(0).boot_ups, 2);
  rig.tick();
  EXPECT_TRUE(rig.r(0).valid);
  const TimeNs second_start = rig.t - kPeriod;

  // A second reboot 10 ms after the start: the next start waits out the
  // 200 ms restart interval (the pre-operational heartbeats keep asking).
  ASSERT_EQ(rig.bus.send(reset), HalStatus::kOk);
  rig.tick();
  EXPECT_EQ(rig.node(0).nmt_state(), NmtState::kPreOperational);
  EXPECT_EQ(rig.st(0).nmt_starts, 2);
  while (rig.t < second_start + 195 * kMs) {
    rig.tick();
    ASSERT_EQ(rig.st(0).nmt_starts, 2) << "at " << rig.t;
  }
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kSilent);  // no TPDOs while pre-operational
  rig.run_for(10 * kMs);
  EXPECT_EQ(rig.st(0).nmt_starts, 3);
  EXPECT_EQ(rig.node(0).nmt_state(), NmtState::kOperational);
  rig.run_for(20 * kMs);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).recoveries, 1);
}

TEST(CanopenFaults, StoppedHeartbeatGetsAStart) {
  Rig rig({0.0});
  rig.run_for(300 * kMs);
  CanFrame stop;
  stop.id = 0x000;
  stop.dlc = 2;
  stop.data[0] = 0x02;
  stop.data[1] = 1;
  ASSERT_EQ(rig.bus.send(stop), HalStatus::kOk);
  rig.run_for(110 * kMs);  // the next heartbeat says stopped
  EXPECT_EQ(rig.st(0).last_nmt_state, 0x04);
  EXPECT_EQ(rig.st(0).nmt_starts, 2);
  EXPECT_EQ(rig.node(0).nmt_state(), NmtState::kOperational);
}

TEST(CanopenFaults, StuckCounterWhileTheOtherWheelMovesIsExcludedThenRecovers) {
  Rig rig({2000.0, 2000.0});
  rig.run_for(200 * kMs);
  ASSERT_TRUE(rig.r(0).valid);
  rig.node(0).set_stuck(true, rig.t);
  const TimeNs stuck_at = rig.t;
  rig.run_for(950 * kMs);
  EXPECT_TRUE(rig.r(0).valid) << "not yet stuck_time_ns (1 s)";
  EXPECT_EQ(rig.st(0).stuck_events, 0);
  rig.run_for(stuck_at + 1010 * kMs - rig.t);
  EXPECT_FALSE(rig.r(0).valid);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kStuck);
  EXPECT_EQ(rig.st(0).stuck_events, 1);
  const std::string stuck = rig.enc->node_error(0);
  EXPECT_EQ(stuck.rfind("node 1: counter unchanged for 1000 ms or more while another wheel moved ", 0), 0u) << stuck;
  EXPECT_TRUE(rig.r(1).valid);
  EXPECT_EQ(rig.st(1).stuck_events, 0);
  rig.run_for(500 * kMs);
  EXPECT_EQ(rig.st(0).stuck_events, 1);

  rig.node(0).set_stuck(false, rig.t);
  rig.run_for(15 * kMs);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).recoveries, 1);
}

TEST(CanopenFaults, StandingStillIsNotStuckNorIsDrivingOffAfterwards) {
  Rig rig({0.0, 0.0});
  rig.run_for(3000 * kMs);
  rig.node(0).set_speed(2000.0, rig.t);
  rig.node(1).set_speed(2000.0, rig.t);
  rig.run_for(100 * kMs);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_TRUE(rig.r(1).valid);
  // One wheel briefly held (a pivot shorter than stuck_time_ns).
  rig.node(0).set_speed(0.0, rig.t);
  rig.run_for(900 * kMs);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).stuck_events + rig.st(1).stuck_events, 0);
}

TEST(CanopenFaults, JumpIsRejectedAndTheUnwrapRebased) {
  CanopenEncodersConfig mc;
  mc.max_counts_per_s = 5000.0;
  Rig rig({1000.0, 1000.0}, mc);
  rig.run_for(100 * kMs);
  ASSERT_TRUE(rig.r(0).valid);
  const std::uint32_t seg0 = rig.r(0).segment;

  rig.node(0).jump(100'000);  // a permanent offset (bad preset)
  rig.tick();
  ASSERT_TRUE(rig.r(0).valid) << "sampled before the jump";
  const std::int64_t c0 = rig.r(0).counts;
  const TimeNs t_jump = rig.t;  // the SYNC that sampled the jumped value
  rig.tick();
  EXPECT_FALSE(rig.r(0).valid);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kJump);
  EXPECT_EQ(rig.st(0).jump_events, 1);
  EXPECT_STREQ(rig.enc->node_error(0),
               "node 1: position jumped 100005 counts in one SYNC, faster than 5000 counts/s; rejected");
  EXPECT_EQ(rig.r(0).segment, seg0 + 1);
  EXPECT_TRUE(rig.r(1).valid) << "only the glitching node is excluded";
  rig.tick();
  ASSERT_TRUE(rig.r(0).valid) << "one glitch costs one sample";
  EXPECT_EQ(rig.st(0).recoveries, 1);
  // Counts go on from the last good value with the motion after the jump.
  const std::int64_t moved = rig.node(0).counts_at(rig.r(0).stamp) - rig.node(0).counts_at(t_jump);
  EXPECT_EQ(moved, 5);
  EXPECT_EQ(rig.r(0).counts, c0 + moved);

  // A one-sample spike: out and back, two samples rejected.
  rig.node(0).jump(-70'000);
  rig.tick();
  rig.node(0).jump(70'000);
  rig.tick();
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kJump);
  rig.tick();
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kJump);
  rig.tick();
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).jump_events, 3);
  EXPECT_EQ(rig.st(1).jump_events, 0);
}

TEST(CanopenFaults, FastestLegalSpeedIsNotAJump) {
  CanopenEncodersConfig mc;
  mc.max_counts_per_s = 5000.0;
  mc.nodes[1].max_counts_per_s = 20'000.0;  // per-node override
  Rig rig({4990.0, -19'990.0}, mc);
  rig.run_for(2000 * kMs);
  EXPECT_EQ(rig.st(0).jump_events, 0);
  EXPECT_EQ(rig.st(1).jump_events, 0);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_TRUE(rig.r(1).valid);
}

TEST(CanopenFaults, BusOffFromTheBusStateInvalidatesAllUntilTpdosFlowAgain) {
  Rig rig({1000.0, 1000.0});
  rig.run_for(100 * kMs);
  ASSERT_TRUE(rig.r(0).valid && rig.r(1).valid);
  const std::uint32_t seg0 = rig.r(0).segment;
  rig.bus.set_state(CanBusState::kBusOff);
  rig.tick();
  for (int i = 0; i < 2; ++i) {
    EXPECT_FALSE(rig.r(i).valid);
    EXPECT_EQ(rig.r(i).health, EncoderHealth::kBusOff);
  }
  EXPECT_EQ(rig.enc->bus_stats().bus_off_events, 1);
  EXPECT_TRUE(rig.enc->bus_stats().bus_off);
  EXPECT_EQ(rig.enc->bus_stats().bus_state, CanBusState::kBusOff);
  EXPECT_EQ(rig.enc->bus_stats().send_failures, 1);
  EXPECT_STREQ(rig.enc->last_error(), "SYNC (COB-ID 0x080) refused by the bus: mock: bus-off");
  EncoderSampleSet set;
  EXPECT_TRUE(rig.enc->take_sample_set(&set));  // the set of the SYNC before: all invalid
  EXPECT_EQ(set.valid_count, 0);

  rig.run_for(1000 * kMs);
  EXPECT_EQ(rig.enc->bus_stats().bus_off_events, 1);
  EXPECT_FALSE(rig.enc->take_sample_set(&set)) << "no SYNC, no set";
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kBusOff);
  EXPECT_EQ(rig.st(0).silent_events, 0) << "bus-off is not blamed on the nodes";

  rig.bus.set_state(CanBusState::kErrorActive);
  rig.tick();  // bus back, SYNC sent
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kBusOff);
  EXPECT_FALSE(rig.enc->bus_stats().bus_off);
  rig.tick();  // its TPDOs arrived
  for (int i = 0; i < 2; ++i) {
    EXPECT_TRUE(rig.r(i).valid) << i;
    EXPECT_EQ(rig.st(i).recoveries, 1);
  }
  EXPECT_EQ(rig.r(0).segment, seg0 + 1);
  EXPECT_EQ(rig.st(0).silent_events, 0);
}

TEST(CanopenFaults, BusOffErrorFrameUntilRestarted) {
  Rig rig({1000.0});
  rig.run_for(50 * kMs);
  ASSERT_TRUE(rig.r(0).valid);
  CanFrame err;
  err.error = true;
  err.id = 0x40;  // CAN_ERR_BUSOFF
  err.dlc = 8;
  rig.bus.inject(err);
  EXPECT_STREQ(rig.enc->last_error(), "");
  rig.tick();
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kBusOff);
  EXPECT_EQ(rig.enc->bus_stats().bus_off_events, 1);
  EXPECT_EQ(rig.enc->bus_stats().error_frames, 1);
  EXPECT_STREQ(rig.enc->last_error(), "bus-off (an error frame): every node is invalid until the bus is back");
  EXPECT_STREQ(rig.enc->node_error(0), "") << "the bus's error, not the node's";
  // A second bus-off report while still off is the same event.
  err.stamp = 0;
  rig.bus.inject(err);
  CanFrame restarted;
  restarted.error = true;
  restarted.id = 0x100;  // CAN_ERR_RESTARTED
  restarted.dlc = 8;
  rig.tick();
  EXPECT_EQ(rig.enc->bus_stats().bus_off_events, 1);
  rig.bus.inject(restarted);
  rig.run_for(15 * kMs);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).recoveries, 1);
  EXPECT_EQ(rig.enc->bus_stats().error_frames, 3);
}

TEST(CanopenFaults, EmcyExcludesTheNodeUntilErrorReset) {
  Rig rig({100.0, 100.0});
  rig.run_for(50 * kMs);
  const std::uint8_t mfr[5] = {1, 2, 3, 4, 5};
  ASSERT_TRUE(rig.node(0).emit_emcy(0x7305, 0x81, mfr, rig.t, rig.bus));
  rig.tick();
  EXPECT_FALSE(rig.r(0).valid);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kEmcy);
  EXPECT_EQ(rig.st(0).emcys, 1);
  EXPECT_EQ(rig.st(0).last_emcy_code, 0x7305);
  EXPECT_EQ(rig.st(0).last_emcy_register, 0x81);
  EXPECT_STREQ(rig.enc->node_error(0), "node 1: EMCY error code 0x7305, error register 0x81");
  EXPECT_TRUE(rig.r(1).valid);
  EncoderSampleSet set;
  ASSERT_TRUE(rig.enc->take_sample_set(&set)) << "an excluded node does not make the set incomplete";
  EXPECT_EQ(set.valid_count, 1);
  rig.run_for(100 * kMs);
  EXPECT_EQ(rig.r(0).health, EncoderHealth::kEmcy);

  ASSERT_TRUE(rig.node(0).emit_emcy(0x0000, 0x00, mfr, rig.t, rig.bus));
  rig.tick();
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.st(0).emcys, 2);
  EXPECT_EQ(rig.st(0).emcy_resets, 1);
  EXPECT_EQ(rig.st(0).last_emcy_code, 0x0000);
  EXPECT_EQ(rig.st(0).recoveries, 1);
  EXPECT_STREQ(rig.enc->node_error(0), "node 1: EMCY error code 0x7305, error register 0x81")
      << "an error reset is no error; the last one is kept";
}

TEST(CanopenFaults, MalformedAndUnexpectedFramesAreCountedAndHarmless) {
  Rig rig({100.0});
  rig.run_for(20 * kMs);
  const auto before = rig.enc->bus_stats();
  auto frame = [](std::uint32_t id, std::uint8_t dlc) {
    CanFrame f;
    f.id = id;
    f.dlc = dlc;
    return f;
  };
  rig.bus.inject(frame(0x181, 2));  // TPDO shorter than its 4-byte mapping
  rig.bus.inject(frame(0x701, 2));  // heartbeat is one byte
  rig.bus.inject(frame(0x081, 4));  // EMCY is eight
  rig.bus.inject(frame(0x181, 9));  // no classic frame has 9 bytes
  rig.bus.inject(frame(0x181, 200));
  CanFrame rtr = frame(0x181, 4);
  rtr.rtr = true;
  rig.bus.inject(rtr);
  CanFrame ext = frame(0x181, 4);
  ext.extended = true;
  rig.bus.inject(ext);
  CanFrame big = frame(0x1FFFFFFF, 8);
  big.extended = true;
  rig.bus.inject(big);
  rig.bus.inject(frame(0x123, 8));
  rig.bus.inject(frame(0x080, 0));  // someone else's SYNC
  CanFrame ctrl;
  ctrl.error = true;
  ctrl.id = 0x04;  // controller problem, not bus-off
  ctrl.dlc = 8;
  rig.bus.inject(ctrl);
  rig.tick();
  const auto& after = rig.enc->bus_stats();
  EXPECT_EQ(after.malformed_frames - before.malformed_frames, 5);
  EXPECT_STREQ(rig.enc->last_error(), "malformed frame COB-ID 0x181 with 200 data bytes; dropped");
  EXPECT_EQ(after.rtr_frames - before.rtr_frames, 1);
  EXPECT_EQ(after.unexpected_cob_ids - before.unexpected_cob_ids, 4);
  EXPECT_EQ(after.error_frames - before.error_frames, 1);
  EXPECT_EQ(after.bus_off_events, 0);
  EXPECT_TRUE(rig.r(0).valid);
  EXPECT_EQ(rig.r(0).counts, rig.node(0).counts_at(rig.r(0).stamp));
}

TEST(CanopenFaults, FailedSyncIsCountedAndNoSetCloses) {
  Rig rig({100.0});
  rig.run_for(20 * kMs);
  EncoderSampleSet set;
  ASSERT_TRUE(rig.enc->take_sample_set(&set));
  const auto syncs = rig.enc->bus_stats().syncs_sent;
  rig.bus.fail_next_send(HalStatus::kIoError, 1);
  rig.tick();  // closes the previous set, its SYNC fails
  EXPECT_TRUE(rig.enc->take_sample_set(&set));
  rig.tick();
  EXPECT_FALSE(rig.enc->take_sample_set(&set));
  EXPECT_EQ(rig.enc->bus_stats().syncs_sent, syncs + 1);
  EXPECT_EQ(rig.enc->bus_stats().send_failures, 1);
  EXPECT_EQ(rig.st(0).missed_syncs, 0) << "a SYNC that never went out is not the node's fault";
  rig.tick();
  EXPECT_TRUE(rig.enc->take_sample_set(&set));
  EXPECT_TRUE(set.readings[0].valid);
}

TEST(CanopenFaults, PollDoesNotAllocateThroughFaultsAndRecoveries) {
  CanopenEncodersConfig mc;
  mc.max_counts_per_s = 50'000.0;
  Rig rig({1000.0, -1000.0, 3000.0, 2000.0}, mc);
  rig.run_for(50 * kMs);
  EncoderSampleSet set;
  int sets = 0;
  const std::uint8_t mfr[5] = {};
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 4000; ++i) {
    if (i == 100) rig.node(0).set_silent(true, rig.t);
    if (i == 600) rig.node(0).set_silent(false, rig.t);
    if (i == 700) rig.node(1).set_stuck(true, rig.t);
    if (i == 1200) rig.node(1).set_stuck(false, rig.t);
    if (i == 1300) rig.node(2).jump(1'000'000);
    if (i == 1400) rig.node(3).emit_emcy(0x1000, 1, mfr, rig.t, rig.bus);
    if (i == 1500) rig.node(3).emit_emcy(0x0000, 0, mfr, rig.t, rig.bus);
    if (i == 1600) rig.bus.set_state(CanBusState::kBusOff);
    if (i == 1700) rig.bus.set_state(CanBusState::kErrorActive);
    rig.tick();
    if (rig.enc->take_sample_set(&set)) ++sets;
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_GT(sets, 3500);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(rig.r(i).valid) << i;
  EXPECT_EQ(rig.st(0).silent_events, 1);
  EXPECT_EQ(rig.st(1).stuck_events, 1);
  EXPECT_EQ(rig.st(2).jump_events, 1);
  EXPECT_EQ(rig.st(3).emcys, 2);
  EXPECT_EQ(rig.enc->bus_stats().bus_off_events, 1);
}

}  // namespace canopen_faults_test
