// The encoder master against scripted CiA 301/406 nodes on the mock bus:
// start-up, SYNC timing, sample attribution, TPDO layouts and wrap-around.
#include "drivers/canopen/canopen_encoders.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sim/devices/canopen_encoder_node.hpp"
#include "hal/mock/mock_can_bus.hpp"

namespace canopen_encoders_test {

using rtfuse::TimeNs;
using rtfuse::drivers::CanopenEncoders;
using rtfuse::drivers::CanopenEncodersConfig;
using rtfuse::drivers::EncoderHealth;
using rtfuse::drivers::EncoderSampleSet;
using rtfuse::hal::CanFrame;
using rtfuse::hal::HalStatus;
using rtfuse::sim::CanopenEncoderConfig;
using rtfuse::sim::CanopenEncoderNode;
using rtfuse::hal::mock::MockCanBus;
using NmtState = rtfuse::sim::canopen::NmtState;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 5 * kMs;  // a 200 Hz loop

// A bus, its encoder nodes and the master, on a manual clock.
struct Rig {
  MockCanBus bus;
  std::vector<std::unique_ptr<CanopenEncoderNode>> nodes;
  std::unique_ptr<CanopenEncoders> enc;
  TimeNs t = 0;

  CanopenEncoderNode& add(const CanopenEncoderConfig& c) {
    nodes.push_back(std::make_unique<CanopenEncoderNode>(c));
    EXPECT_TRUE(bus.attach(*nodes.back()));
    return *nodes.back();
  }
  void make(const CanopenEncodersConfig& c) {
    std::string error;
    enc = CanopenEncoders::create(bus, c, &error);
    ASSERT_NE(enc, nullptr) << error;
  }
  void tick() {
    t += kPeriod;
    bus.set_time(t);
    enc->poll(t);
  }
  void run(int ticks) {
    for (int i = 0; i < ticks; ++i) tick();
  }
};

CanopenEncoderConfig node_cfg(std::uint8_t id, double speed = 0.0) {
  CanopenEncoderConfig c;
  c.node_id = id;
  c.speed_counts_per_s = speed;
  return c;
}

CanopenEncodersConfig master_cfg(std::initializer_list<std::uint8_t> ids) {
  CanopenEncodersConfig c;
  for (std::uint8_t id : ids) c.nodes[static_cast<std::size_t>(c.node_count++)].node_id = id;
  return c;
}

TEST(CanopenEncoders, CreateRefusesAnInvalidConfigWithTheReason) {
  MockCanBus bus;
  CanopenEncodersConfig c = master_cfg({1});
  c.nodes[0].tpdo.width_bits = 20;
  std::string error;
  EXPECT_EQ(CanopenEncoders::create(bus, c, &error), nullptr);
  EXPECT_NE(error.find("nodes[0].tpdo.width_bits = 20"), std::string::npos) << error;
}

TEST(CanopenEncoders, StartSendsNmtStartToEachNodeAndTheyGoOperational) {
  Rig rig;
  CanopenEncoderNode& a = rig.add(node_cfg(3));
  CanopenEncoderNode& b = rig.add(node_cfg(9));
  rig.make(master_cfg({3, 9}));
  ASSERT_TRUE(rig.enc->start(0));
  ASSERT_EQ(rig.bus.sent_count(), 2);
  EXPECT_EQ(rig.bus.sent(0).id, 0x000U);
  EXPECT_EQ(rig.bus.sent(0).dlc, 2);
  EXPECT_EQ(rig.bus.sent(0).data[0], 0x01);
  EXPECT_EQ(rig.bus.sent(0).data[1], 3);
  EXPECT_EQ(rig.bus.sent(1).data[1], 9);
  EXPECT_EQ(a.nmt_state(), NmtState::kOperational);
  EXPECT_EQ(b.nmt_state(), NmtState::kOperational);
  EXPECT_EQ(rig.enc->node_stats(0).nmt_starts, 1);
  EXPECT_EQ(rig.enc->bus_stats().nmt_sent, 2);
  // The boot-ups queued before the start are old news: no second start.
  rig.run(3);
  EXPECT_EQ(rig.enc->bus_stats().nmt_sent, 2);
  EXPECT_EQ(rig.enc->node_stats(0).boot_ups, 1);
}

TEST(CanopenEncoders, StartReportsARefusedSendWithTheBusError) {
  Rig rig;
  rig.add(node_cfg(1));
  rig.add(node_cfg(2));
  rig.make(master_cfg({1, 2}));
  rig.bus.fail_next_send(HalStatus::kIoError, 1);
  EXPECT_FALSE(rig.enc->start(0));
  EXPECT_EQ(rig.enc->bus_stats().send_failures, 1);
  EXPECT_EQ(rig.enc->bus_stats().nmt_sent, 1);  // node 2 was still started
  EXPECT_STREQ(rig.enc->last_error(),
               "NMT start of node 1 (COB-ID 0x000) refused by the bus: mock: injected send failure");
  EXPECT_EQ(rig.nodes[1]->nmt_state(), NmtState::kOperational);
}

TEST(CanopenEncoders, EveryPollSendsOneSync) {
  Rig rig;
  rig.add(node_cfg(1));
  rig.make(master_cfg({1}));
  ASSERT_TRUE(rig.enc->start(0));
  rig.bus.clear_sent();
  rig.run(10);
  ASSERT_EQ(rig.bus.sent_count(), 10);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(rig.bus.sent(i).id, 0x080U);
    EXPECT_EQ(rig.bus.sent(i).dlc, 0);
    EXPECT_EQ(rig.bus.sent(i).stamp, (i + 1) * kPeriod);
  }
  EXPECT_EQ(rig.enc->bus_stats().syncs_sent, 10);
}

TEST(CanopenEncoders, CustomSyncCobIdIsUsed) {
  Rig rig;
  CanopenEncodersConfig c = master_cfg({1});
  c.sync_cob_id = 0x090;
  rig.make(c);
  rig.tick();
  ASSERT_EQ(rig.bus.sent_count(), 1);
  EXPECT_EQ(rig.bus.sent(0).id, 0x090U);
}

TEST(CanopenEncoders, PositionIsStampedWithTheSyncThatSampledIt) {
  Rig rig;
  CanopenEncoderConfig nc = node_cfg(1, 1000.0);
  nc.initial_position = 5000;
  CanopenEncoderNode& node = rig.add(nc);
  rig.make(master_cfg({1}));
  ASSERT_TRUE(rig.enc->start(0));
  rig.tick();  // SYNC 1 at 5 ms; the node answers with counts at 5 ms
  EXPECT_EQ(rig.enc->reading(0).health, EncoderHealth::kNotStarted);
  EXPECT_FALSE(rig.enc->reading(0).valid);
  rig.tick();  // the answer is processed at 10 ms, stamped 5 ms
  const auto& r = rig.enc->reading(0);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.health, EncoderHealth::kOk);
  EXPECT_EQ(r.counts, 5005);  // 5000 + 1000 counts/s * 5 ms
  EXPECT_EQ(r.counts, node.counts_at(5 * kMs));
  EXPECT_EQ(r.stamp, 5 * kMs);
  EXPECT_EQ(r.sample_seq, 1);
  EXPECT_EQ(rig.enc->node_stats(0).tpdos, 1);
}

TEST(CanopenEncoders, TpdoReceivedBetweenSyncsBelongsToTheEarlierSync) {
  Rig rig;
  rig.make(master_cfg({4}));
  rig.tick();  // SYNC 1 at 5 ms
  CanFrame f;
  f.id = 0x184;
  f.dlc = 4;
  f.data[0] = 0x10;
  rig.bus.inject_at(f, 8 * kMs);  // 3 ms after SYNC 1: bus latency, not sample time
  rig.tick();                     // SYNC 2 at 10 ms
  EXPECT_TRUE(rig.enc->reading(0).valid);
  EXPECT_EQ(rig.enc->reading(0).stamp, 5 * kMs);
  EXPECT_EQ(rig.enc->reading(0).sample_seq, 1);
  EXPECT_EQ(rig.enc->reading(0).counts, 0x10);
  // A frame stamped before any SYNC was sent cannot be attributed: dropped.
  f.data[0] = 0x20;
  rig.bus.inject_at(f, 1 * kMs);
  rig.tick();
  EXPECT_EQ(rig.enc->bus_stats().stale_tpdos, 1);
  EXPECT_EQ(rig.enc->reading(0).counts, 0x10);
}

TEST(CanopenEncoders, LeftoverTpdosAreAttributedByStampNotByArrival) {
  Rig rig;
  rig.make(master_cfg({4}));
  rig.run(2);  // SYNC 1 at 5 ms, SYNC 2 at 10 ms; set 1 closed without node 4
  CanFrame f;
  f.id = 0x184;
  f.dlc = 4;
  f.data[0] = 100;
  rig.bus.inject_at(f, 8 * kMs);  // answer to SYNC 1, read only now: late
  f.data[0] = 103;
  rig.bus.inject_at(f, 12 * kMs);  // answer to SYNC 2
  f.data[0] = 111;
  rig.bus.inject_at(f, 13 * kMs);  // a second answer to SYNC 2
  rig.tick();
  EXPECT_EQ(rig.enc->bus_stats().late_tpdos, 1);
  EXPECT_EQ(rig.enc->bus_stats().stale_tpdos, 1);
  EXPECT_EQ(rig.enc->node_stats(0).tpdos, 2);
  const auto& r = rig.enc->reading(0);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.sample_seq, 2);
  EXPECT_EQ(r.stamp, 10 * kMs);
  EXPECT_EQ(r.counts, 103);
}

TEST(CanopenEncoders, SampleSetCompletesWhenAllNodesAnsweredTheSameSync) {
  Rig rig;
  rig.add(node_cfg(1, 2000.0));
  rig.add(node_cfg(2, -2000.0));
  rig.make(master_cfg({1, 2}));
  ASSERT_TRUE(rig.enc->start(0));
  EncoderSampleSet set;
  rig.tick();
  EXPECT_FALSE(rig.enc->take_sample_set(&set));  // SYNC 1 sent, nothing answered yet
  rig.tick();
  ASSERT_TRUE(rig.enc->take_sample_set(&set));
  EXPECT_FALSE(rig.enc->take_sample_set(&set));  // once per set
  EXPECT_EQ(set.seq, 1);
  EXPECT_EQ(set.stamp, 5 * kMs);
  EXPECT_EQ(set.node_count, 2);
  EXPECT_EQ(set.valid_count, 2);
  EXPECT_EQ(set.readings[0].counts, 10);
  EXPECT_EQ(set.readings[1].counts, 4'294'967'286LL);  // unsigned 32-bit: -10 reads as 2^32 - 10
  rig.tick();
  ASSERT_TRUE(rig.enc->take_sample_set(&set));
  EXPECT_EQ(set.seq, 2);
  EXPECT_EQ(set.readings[0].counts, 20);
  EXPECT_EQ(set.readings[1].counts, 4'294'967'276LL);  // continuous through the decrease
  EXPECT_EQ(rig.enc->bus_stats().complete_sets, 2);
}

struct WrapCase {
  int width_bits;
  bool is_signed;
  std::int64_t initial;
  double speed;  // counts/s; |speed| * 5 ms < half the range
};

class CanopenEncodersWrap : public ::testing::TestWithParam<WrapCase> {};

TEST_P(CanopenEncodersWrap, CountsStayContinuousThroughManyWraps) {
  const WrapCase& p = GetParam();
  Rig rig;
  CanopenEncoderConfig nc = node_cfg(7, p.speed);
  nc.position_width = static_cast<std::uint8_t>(p.width_bits / 8);
  nc.position_signed = p.is_signed;
  nc.initial_position = p.initial;
  CanopenEncoderNode& node = rig.add(nc);
  CanopenEncodersConfig mc = master_cfg({7});
  mc.nodes[0].tpdo.width_bits = static_cast<std::uint8_t>(p.width_bits);
  mc.nodes[0].tpdo.is_signed = p.is_signed;
  rig.make(mc);
  ASSERT_TRUE(rig.enc->start(0));
  const double range = static_cast<double>(std::uint64_t{1} << p.width_bits);
  const int ticks = 2000;  // 10 s
  int checked = 0;
  bool first = true;
  std::int64_t counts0 = 0;
  std::int64_t truth0 = 0;
  for (int i = 0; i < ticks; ++i) {
    rig.tick();
    const auto& r = rig.enc->reading(0);
    if (!r.valid) continue;
    if (first) {
      // The first sample is the value on the wire, the unwrap goes on from it.
      EXPECT_EQ(r.counts, node.position_value(r.stamp));
      counts0 = r.counts;
      truth0 = node.counts_at(r.stamp);
      first = false;
    }
    ASSERT_EQ(r.counts - counts0, node.counts_at(r.stamp) - truth0) << "at " << r.stamp;
    ++checked;
  }
  EXPECT_EQ(checked, ticks - 1);
  // It really went round the counter more than once.
  EXPECT_GT(std::abs(p.speed) * 10.0, 2.0 * range);
}

INSTANTIATE_TEST_SUITE_P(
    CanopenWidths, CanopenEncodersWrap,
    ::testing::Values(WrapCase{8, false, 250, 20'000.0},                // 100 counts per SYNC of 256
                      WrapCase{8, false, 3, -20'000.0},
                      WrapCase{8, true, 120, 25'000.0},                 // 125 counts per SYNC: just under half
                      WrapCase{8, true, -100, -20'000.0},
                      WrapCase{16, false, 65'000, 3'000'000.0},
                      WrapCase{16, true, -32'000, -3'000'000.0},
                      WrapCase{24, false, 16'000'000, 800'000'000.0},
                      WrapCase{24, true, 8'000'000, -800'000'000.0},
                      WrapCase{32, false, 4'294'967'000LL, 200'000'000'000.0},
                      WrapCase{32, true, 2'147'483'000LL, -200'000'000'000.0}));

TEST(CanopenEncoders, MoreThanHalfTheRangePerSyncIsReadBackwards) {
  // The documented limit, shown: 150 counts per SYNC on an 8-bit counter is
  // indistinguishable from 106 counts the other way.
  Rig rig;
  CanopenEncoderConfig nc = node_cfg(2, 30'000.0);
  nc.position_width = 1;
  rig.add(nc);
  CanopenEncodersConfig mc = master_cfg({2});
  mc.nodes[0].tpdo.width_bits = 8;
  rig.make(mc);
  ASSERT_TRUE(rig.enc->start(0));
  rig.run(2);
  const std::int64_t c1 = rig.enc->reading(0).counts;
  rig.tick();
  EXPECT_EQ(rig.enc->reading(0).counts - c1, 150 - 256);
}

TEST(CanopenEncoders, CustomCobIdOffsetAndWidth) {
  Rig rig;
  CanopenEncoderConfig nc = node_cfg(5, 0.0);
  nc.tpdo_cob_id = 0x285;  // TPDO2
  nc.position_offset = 3;
  nc.position_width = 2;
  nc.position_signed = true;
  nc.tpdo_dlc = 8;
  nc.initial_position = -300;
  rig.add(nc);
  CanopenEncodersConfig mc = master_cfg({5});
  mc.nodes[0].tpdo = {0x285, 3, 16, true};
  rig.make(mc);
  ASSERT_TRUE(rig.enc->start(0));
  rig.run(2);
  ASSERT_TRUE(rig.enc->reading(0).valid);
  EXPECT_EQ(rig.enc->reading(0).counts, -300);
  EXPECT_EQ(rig.enc->bus_stats().unexpected_cob_ids, 0);
}

TEST(CanopenEncoders, ATpdoOnTheDefaultIdIsUnexpectedWhenMappedElsewhere) {
  Rig rig;
  rig.add(node_cfg(5, 0.0));  // sends on 0x185
  CanopenEncodersConfig mc = master_cfg({5});
  mc.nodes[0].tpdo.cob_id = 0x285;
  rig.make(mc);
  ASSERT_TRUE(rig.enc->start(0));
  rig.run(3);
  EXPECT_EQ(rig.enc->bus_stats().unexpected_cob_ids, 2);
  EXPECT_FALSE(rig.enc->reading(0).valid);
}

TEST(CanopenEncoders, PollWithoutStartStartsNodesWhenTheirBootUpIsSeen) {
  Rig rig;
  CanopenEncoderNode& node = rig.add(node_cfg(1, 100.0));
  rig.make(master_cfg({1}));
  rig.tick();
  EXPECT_EQ(node.nmt_state(), NmtState::kOperational);
  EXPECT_EQ(rig.enc->node_stats(0).nmt_starts, 1);
  rig.run(2);
  EXPECT_TRUE(rig.enc->reading(0).valid);
}

TEST(CanopenEncoders, PollDrainsAtMostTheConfiguredNumberOfFrames) {
  Rig rig;
  CanopenEncodersConfig mc = master_cfg({1});
  mc.max_frames_per_poll = 20;
  rig.make(mc);
  CanFrame junk;
  junk.id = 0x555;
  junk.dlc = 1;
  for (int i = 0; i < 50; ++i) rig.bus.inject(junk);
  rig.tick();
  EXPECT_EQ(rig.enc->bus_stats().frames_received, 20);
  EXPECT_EQ(rig.enc->bus_stats().rx_limit_hits, 1);
  EXPECT_EQ(rig.bus.pending(), 30);
  rig.run(2);
  EXPECT_EQ(rig.enc->bus_stats().frames_received, 50);
  EXPECT_EQ(rig.enc->bus_stats().unexpected_cob_ids, 50);
}

}  // namespace canopen_encoders_test
