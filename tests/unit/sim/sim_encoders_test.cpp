// The simulated robot's CAN side: CiA 406 encoder nodes whose positions are
// the ground truth at the SYNC's time, with dropouts and slip.
#include "sim/sim_encoders.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hal/mock/sim_clock.hpp"
#include "sim/truth_trajectory.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::sim {
namespace sim_encoders_test {

using hal::CanFrame;
using hal::HalStatus;
using hal::mock::SimClock;
using NmtState = sim::canopen::NmtState;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSec = 1'000 * kMs;
constexpr TimeNs kT0 = 500 * kSec;
constexpr double kPi = 3.14159265358979323846;

DriveScenario straight_drive() {
  DriveScenario sc;
  PathSegment g;
  g.type = SegmentType::kStraight;
  g.length_m = 20.0;
  g.speed_mps = 1.2;
  sc.path = {g};
  sc.robot.track_width_m = 0.5;
  sc.robot.wheel_radius_m = 0.1;
  sc.robot.counts_per_rev = 4096;
  sc.robot.gear_ratio = 2.0;
  sc.robot.encoder_bits = 32;
  sc.robot.heartbeat_period_ns = 100 * kMs;
  sc.robot.wheel_count = 2;
  sc.robot.wheels[0] = SimWheel{1, true, 0.01};
  sc.robot.wheels[1] = SimWheel{2, false, 0.0};
  return sc;
}

CanFrame sync_frame() {
  CanFrame f;
  f.id = 0x080;
  return f;
}

CanFrame nmt_start_all() {
  CanFrame f;
  f.id = 0x000;
  f.dlc = 2;
  f.data[0] = 0x01;
  f.data[1] = 0;
  return f;
}

std::vector<CanFrame> drain(SimEncoders& bus) {
  std::vector<CanFrame> all;
  CanFrame out[32];
  HalStatus st = HalStatus::kOk;
  int n = 0;
  while ((n = bus.receive(out, 32, 0, &st)) > 0) all.insert(all.end(), out, out + n);
  return all;
}

const CanFrame* find(const std::vector<CanFrame>& frames, std::uint32_t id) {
  for (const CanFrame& f : frames) {
    if (f.id == id) return &f;
  }
  return nullptr;
}

std::int64_t le_value(const CanFrame& f, int bytes, bool is_signed) {
  std::uint64_t raw = 0;
  for (int i = 0; i < bytes; ++i) raw |= std::uint64_t{f.data[i]} << (8 * i);
  const int bits = 8 * bytes;
  if (is_signed && (raw >> (bits - 1)) != 0) return static_cast<std::int64_t>(raw) - (std::int64_t{1} << bits);
  return static_cast<std::int64_t>(raw);
}

// Counts from the truth by hand: angle = distance / true radius.
std::int64_t expected_counts(const DriveScenario& sc, const TruthState& s, int wheel) {
  const double radius = sc.robot.wheel_radius_m * (1.0 + sc.robot.wheels[wheel].radius_error);
  return static_cast<std::int64_t>(
      std::floor(s.wheel_distance[wheel] / radius * sc.robot.counts_per_rev * sc.robot.gear_ratio / (2.0 * kPi)));
}

TEST(SimEncoders, NodesBootAndAnswerSyncWithTheTruthAtTheSyncTime) {
  const DriveScenario sc = straight_drive();
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimEncoders bus(sc, truth, clock, kT0);
  auto frames = drain(bus);
  ASSERT_EQ(frames.size(), 2u);  // the boot-ups
  EXPECT_EQ(frames[0].id, 0x701u);
  EXPECT_EQ(frames[1].id, 0x702u);
  EXPECT_EQ(frames[0].data[0], 0x00);
  EXPECT_EQ(frames[0].stamp, kT0);

  // Pre-operational: SYNC gets no answer.
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  EXPECT_TRUE(drain(bus).empty());
  ASSERT_EQ(bus.send(nmt_start_all()), HalStatus::kOk);
  EXPECT_EQ(bus.node(0).nmt_state(), NmtState::kOperational);

  std::int64_t last_left = -1;
  for (TimeNs t : {kT0 + 1'500 * kMs, kT0 + 5'005 * kMs, kT0 + 10'000 * kMs}) {
    clock.set(t);
    ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
    frames = drain(bus);
    const CanFrame* left = find(frames, 0x181);
    const CanFrame* right = find(frames, 0x182);
    ASSERT_NE(left, nullptr);
    ASSERT_NE(right, nullptr);
    EXPECT_EQ(left->stamp, t);
    EXPECT_EQ(left->dlc, 4);
    const TruthState s = truth.truth_at(ns_to_sec(t - kT0));
    EXPECT_EQ(le_value(*left, 4, false), expected_counts(sc, s, 0));
    EXPECT_EQ(le_value(*right, 4, false), expected_counts(sc, s, 1));
    EXPECT_EQ(le_value(*left, 4, false), wheel_counts(sc.robot, s, 0));
    EXPECT_GT(le_value(*left, 4, false), last_left);
    last_left = le_value(*left, 4, false);
  }
  // 10 s in: 1.2 m/s cruise since 2.4 s, so 1.44 + 7.6 * 1.2 = 10.56 m rolled;
  // the left wheel is 1 % larger, so it turned 1 % less.
  const double right_turns = 10.56 / (2.0 * kPi * 0.1);
  EXPECT_NEAR(static_cast<double>(last_left), right_turns / 1.01 * 4096 * 2.0, 1.0);
  // One TPDO per node per SYNC while Operational.
  EXPECT_EQ(bus.node(1).tpdo_count(), 3);
}

TEST(SimEncoders, DropoutSilencesTheNodeThenItBootsLikeAPowerCycledNode) {
  DriveScenario sc = straight_drive();
  sc.dropout_count = 1;
  sc.dropouts[0] = EncoderDropout{2, 2.0, 2.0};
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimEncoders bus(sc, truth, clock, kT0);
  drain(bus);
  ASSERT_EQ(bus.send(nmt_start_all()), HalStatus::kOk);

  int right_tpdos_in_window = 0, right_heartbeats_in_window = 0, left_tpdos_in_window = 0;
  std::vector<CanFrame> after;
  // A 200 Hz loop: receive, then SYNC, as the encoder driver polls.
  for (TimeNs t = kT0; t <= kT0 + 5 * kSec; t += 5 * kMs) {
    clock.set(t);
    const auto frames = drain(bus);
    for (const CanFrame& f : frames) {
      const bool in_window = f.stamp > kT0 + 2 * kSec && f.stamp < kT0 + 4 * kSec;
      if (in_window && f.id == 0x182) ++right_tpdos_in_window;
      if (in_window && f.id == 0x702) ++right_heartbeats_in_window;
      if (in_window && f.id == 0x181) ++left_tpdos_in_window;
      if (f.stamp >= kT0 + 4 * kSec) after.push_back(f);
    }
    ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  }
  EXPECT_EQ(right_tpdos_in_window, 0);
  EXPECT_EQ(right_heartbeats_in_window, 0);
  EXPECT_GT(left_tpdos_in_window, 390);
  EXPECT_EQ(bus.reboots(1), 1);
  EXPECT_EQ(bus.node(1).boot_count(), 2);
  // Back at exactly 4 s with a boot-up, then Pre-operational heartbeats and
  // no TPDOs until the master starts it again.
  const CanFrame* boot = find(after, 0x702);
  ASSERT_NE(boot, nullptr);
  EXPECT_EQ(boot->stamp, kT0 + 4 * kSec);
  EXPECT_EQ(boot->dlc, 1);
  EXPECT_EQ(boot->data[0], 0x00);
  EXPECT_EQ(find(after, 0x182), nullptr);
  int preop_heartbeats = 0;
  for (const CanFrame& f : after) preop_heartbeats += f.id == 0x702 && f.data[0] == 0x7F;
  EXPECT_GE(preop_heartbeats, 9);
  EXPECT_EQ(bus.node(1).nmt_state(), NmtState::kPreOperational);

  ASSERT_EQ(bus.send(nmt_start_all()), HalStatus::kOk);
  clock.set(kT0 + 5'500 * kMs);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  const auto frames = drain(bus);
  const CanFrame* tpdo = find(frames, 0x182);
  ASSERT_NE(tpdo, nullptr);
  EXPECT_EQ(le_value(*tpdo, 4, false), expected_counts(sc, truth.truth_at(5.5), 1));  // the shaft kept turning
}

TEST(SimEncoders, SlipEpisodeAddsItsFractionToTheCounts) {
  DriveScenario sc = straight_drive();
  sc.robot.wheels[0].radius_error = 0.0;
  sc.slip.episode_count = 1;
  sc.slip.episodes[0] = SlipEpisode{5.0, 3.0, 0x01, 0.3};  // left wheel, at cruise
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimEncoders bus(sc, truth, clock, kT0);
  ASSERT_EQ(bus.send(nmt_start_all()), HalStatus::kOk);
  auto counts_at = [&](double t) {
    clock.set(kT0 + sec_to_ns(t));
    drain(bus);
    EXPECT_EQ(bus.send(sync_frame()), HalStatus::kOk);
    const auto frames = drain(bus);
    const CanFrame* l = find(frames, 0x181);
    const CanFrame* r = find(frames, 0x182);
    EXPECT_TRUE(l != nullptr && r != nullptr);
    return std::make_pair(l ? le_value(*l, 4, false) : 0, r ? le_value(*r, 4, false) : 0);
  };
  const auto before = counts_at(4.5);
  const auto start = counts_at(5.0);
  const auto end = counts_at(8.0);
  const auto later = counts_at(9.0);
  // Same counts on both sides before; during the episode the left wheel
  // turns 1.3 times as far: 3 s * 1.2 m/s = 3.6 m, i.e. 11'735 counts on the right.
  EXPECT_LE(std::abs(before.first - before.second), 1);
  const double left = static_cast<double>(end.first - start.first);
  const double right = static_cast<double>(end.second - start.second);
  EXPECT_NEAR(right, 3.6 / (2.0 * kPi * 0.1) * 4096 * 2.0, 2.0);
  EXPECT_NEAR(left / right, 1.3, 2e-4);
  // After it, both count alike again.
  EXPECT_LE(std::abs((later.first - end.first) - (later.second - end.second)), 2);
}

TEST(SimEncoders, NarrowAndSignedEncodersWrapAndInvertedSidesCountDown) {
  DriveScenario sc = straight_drive();
  sc.robot.encoder_bits = 12;
  sc.robot.encoder_signed = true;
  sc.robot.invert_right = true;
  TruthTrajectory truth(sc);
  SimClock clock(kT0);
  SimEncoders bus(sc, truth, clock, kT0);
  ASSERT_EQ(bus.send(nmt_start_all()), HalStatus::kOk);
  clock.set(kT0 + 7 * kSec);
  drain(bus);
  ASSERT_EQ(bus.send(sync_frame()), HalStatus::kOk);
  const auto frames = drain(bus);
  const CanFrame* l = find(frames, 0x181);
  const CanFrame* r = find(frames, 0x182);
  ASSERT_TRUE(l != nullptr && r != nullptr);
  EXPECT_EQ(l->dlc, 2);  // 12 bits go in two bytes
  const TruthState s = truth.truth_at(7.0);
  const std::int64_t left = expected_counts(sc, s, 0);
  const std::int64_t right = -expected_counts(sc, s, 1) - 1;  // floor of the negated angle
  EXPECT_GT(left, 4096 * 20);  // many wraps
  EXPECT_EQ(le_value(*l, 2, true), wrap_position(left, 12, true));
  EXPECT_EQ(le_value(*r, 2, true), wrap_position(right, 12, true));
  EXPECT_GE(le_value(*l, 2, true), -2048);
  EXPECT_LT(le_value(*l, 2, true), 2048);
  EXPECT_EQ(wheel_counts(sc.robot, s, 1), right);
}

TEST(SimEncoders, WrapPositionFollowsTheEncoderWidth) {
  EXPECT_EQ(wrap_position(4095, 12, false), 4095);
  EXPECT_EQ(wrap_position(4096, 12, false), 0);
  EXPECT_EQ(wrap_position(-1, 12, false), 4095);
  EXPECT_EQ(wrap_position(2047, 12, true), 2047);
  EXPECT_EQ(wrap_position(2048, 12, true), -2048);
  EXPECT_EQ(wrap_position(-1, 32, false), 4294967295);
  EXPECT_EQ(wrap_position(std::int64_t{1} << 31, 32, true), -(std::int64_t{1} << 31));
  EXPECT_EQ(wrap_position(300, 8, false), 44);
}

TEST(SimEncoders, SameScenarioSameFramesAndNoAllocationPerCall) {
  DriveScenario sc = straight_drive();
  sc.slip.noise_fraction = 0.02;
  sc.dropout_count = 1;
  sc.dropouts[0] = EncoderDropout{1, 3.0, 1.0};
  TruthTrajectory truth_a(sc);
  TruthTrajectory truth_b(sc);
  SimClock clock_a(kT0), clock_b(kT0);
  SimEncoders a(sc, truth_a, clock_a, kT0);
  SimEncoders b(sc, truth_b, clock_b, kT0);
  CanFrame fa[64], fb[64];
  HalStatus st = HalStatus::kOk;
  std::size_t total = 0;
  bool same = true;
  {
    rtfuse::test::AllocScope scope;
    a.send(nmt_start_all());
    b.send(nmt_start_all());
    for (TimeNs t = kT0; t < kT0 + 8 * kSec; t += 5 * kMs) {
      clock_a.set(t);
      clock_b.set(t);
      const int na = a.receive(fa, 64, 0, &st);
      const int nb = b.receive(fb, 64, 0, &st);
      same = same && na == nb;
      for (int i = 0; i < na && i < nb; ++i) {
        same = same && fa[i].id == fb[i].id && fa[i].stamp == fb[i].stamp && fa[i].dlc == fb[i].dlc;
        for (int j = 0; j < 8; ++j) same = same && fa[i].data[j] == fb[i].data[j];
      }
      total += static_cast<std::size_t>(na);
      a.send(sync_frame());
      b.send(sync_frame());
    }
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_TRUE(same);
  // Node 2 answers 1600 SYNCs, node 1 the 600 before its dropout (it comes
  // back Pre-operational and nobody restarts it), plus 160 heartbeats.
  EXPECT_GT(total, 2300u);
  EXPECT_LT(total, 2400u);
}

}  // namespace sim_encoders_test
}  // namespace rtfuse::sim
