// Record with the decorators on the mock buses, then replay the same calls on
// the replay buses: every call gets back exactly what the mock returned.
#include <gtest/gtest.h>

#include <vector>

#include "hal/mock/mock_can_bus.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "hal/replay/replay_can_bus.hpp"
#include "hal/replay/replay_clock.hpp"
#include "hal/replay/replay_gpio.hpp"
#include "hal/replay/replay_i2c_bus.hpp"
#include "hal/mock/scripted_gpio.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/recording_can_bus.hpp"
#include "hal/recording_clock.hpp"
#include "hal/recording_gpio.hpp"
#include "hal/recording_i2c_bus.hpp"

namespace replay_buses_test {

using namespace rtfuse;  // NOLINT
using hal::BusEvent;
using hal::CanBus;
using hal::CanBusState;
using hal::CanFrame;
using hal::Clock;
using hal::GpioEdge;
using hal::GpioEdgeSource;
using hal::HalStatus;
using hal::I2cBus;
namespace mock = hal::mock;
namespace replay = hal::replay;

// What a driver saw from one call, to compare recording with replay.
struct Seen {
  HalStatus status = HalStatus::kOk;
  int n = 0;
  std::vector<std::uint8_t> bytes;
  std::vector<std::uint32_t> ids;
  std::vector<TimeNs> stamps;
  CanBusState state = CanBusState::kUnknown;
  bool operator==(const Seen& o) const {
    return status == o.status && n == o.n && bytes == o.bytes && ids == o.ids && stamps == o.stamps &&
           state == o.state;
  }
};

// A fixed driver-like script over the interfaces only.
std::vector<Seen> run_script(CanBus& can, I2cBus& i2c, GpioEdgeSource& drdy, Clock& clock) {
  std::vector<Seen> seen;
  CanFrame sync;
  sync.id = 0x080;
  for (int tick = 0; tick < 5; ++tick) {
    Seen s;
    s.status = can.send(sync);
    s.state = can.state();
    seen.push_back(s);
    CanFrame out[4];
    Seen r;
    r.n = can.receive(out, 4, 0, &r.status);
    for (int i = 0; i < r.n; ++i) {
      r.ids.push_back(out[i].id);
      r.stamps.push_back(out[i].stamp);
      r.bytes.insert(r.bytes.end(), out[i].data, out[i].data + out[i].dlc);
    }
    r.state = can.state();
    seen.push_back(r);
    GpioEdge e;
    Seen g;
    g.status = drdy.wait_edge(1'000'000, &e);
    if (g.status == HalStatus::kOk) g.stamps.push_back(e.stamp);
    seen.push_back(g);
    std::uint8_t buf[14] = {};
    Seen d;
    d.status = i2c.read_registers(0x68, 0x3B, buf, 14);
    d.bytes.assign(buf, buf + 14);
    d.n = static_cast<int>(i2c.retries());
    seen.push_back(d);
    Seen c;
    c.stamps.push_back(clock.now());
    seen.push_back(c);
    clock.sleep_until(c.stamps.back() + 5'000'000);
  }
  return seen;
}

TEST(HalReplayBuses, ReplayReturnsWhatTheRecordedBusesReturned) {
  // --- record
  mock::SimClock sim(1'000'000'000);
  mock::MockCanBus can({}, &sim);
  sim::MpuRegisterFile chip(sim::MpuChip::kMpu6050);
  mock::MockI2cBus i2c;
  ASSERT_TRUE(i2c.attach(0x68, chip));
  ASSERT_EQ(i2c.write_register(0x68, 0x6B, 0x01), HalStatus::kOk);
  mock::ScriptedEdgeSource drdy;
  for (int i = 0; i < 3; ++i) drdy.push(1'000'000'000 + i * 5'000'000);
  for (int i = 0; i < 4; ++i) {
    CanFrame f;
    f.id = 0x181;
    f.dlc = 4;
    f.data[0] = static_cast<std::uint8_t>(i);
    can.inject_at(f, 900'000'000 + i);
  }
  i2c.fail_next(HalStatus::kBusError, 1);

  SpscRing<BusEvent> loop_ring(256);
  hal::RecordingCanBus rcan(can, loop_ring, 0, &sim);
  hal::RecordingI2cBus ri2c(i2c, loop_ring, 1, &sim);
  hal::RecordingEdgeSource rdrdy(drdy, loop_ring, 2, &sim);
  hal::RecordingClock rclock(sim, loop_ring, 3);
  const std::vector<Seen> live = run_script(rcan, ri2c, rdrdy, rclock);

  // --- replay
  replay::ReplayStream stream("loop");
  BusEvent ev;
  std::int64_t n = 0;
  while (loop_ring.try_pop(ev)) stream.append(ev, 100 + n++);
  EXPECT_EQ(stream.size(), 30u);  // 5 ticks x (send, receive, edge, read, now, sleep)
  replay::ReplayCanBus pcan(stream, 0);
  replay::ReplayI2cBus pi2c(stream, 1);
  replay::ReplayEdgeSource pdrdy(stream, 2);
  replay::ReplayClock pclock(stream, 3);
  const std::vector<Seen> replayed = run_script(pcan, pi2c, pdrdy, pclock);

  EXPECT_FALSE(stream.diverged()) << stream.divergence();
  EXPECT_TRUE(stream.at_end());
  ASSERT_EQ(replayed.size(), live.size());
  for (std::size_t i = 0; i < live.size(); ++i) EXPECT_TRUE(replayed[i] == live[i]) << "call " << i;
  // The script saw real variety: frames on the first receive, a recovered
  // retry, edges then timeouts.
  EXPECT_EQ(live[1].n, 4);
  EXPECT_EQ(live[3].n, 1);
  EXPECT_EQ(live[2].status, HalStatus::kOk);
  EXPECT_EQ(live[12].status, HalStatus::kOk);
  EXPECT_EQ(live[17].status, HalStatus::kTimeout);
}

}  // namespace replay_buses_test
