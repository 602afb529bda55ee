#include "hal/replay/replay_stream.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hal/replay/replay_can_bus.hpp"
#include "hal/replay/replay_clock.hpp"
#include "hal/replay/replay_gpio.hpp"
#include "hal/replay/replay_i2c_bus.hpp"
#include "support/alloc_counter.hpp"

namespace replay_stream_test {

using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::CanFrame;
using rtfuse::hal::GpioEdge;
using rtfuse::hal::HalStatus;
using rtfuse::hal::replay::DivergenceKind;
using rtfuse::hal::replay::ReplayCanBus;
using rtfuse::hal::replay::ReplayClock;
using rtfuse::hal::replay::ReplayEdgeSource;
using rtfuse::hal::replay::ReplayGpioOutput;
using rtfuse::hal::replay::ReplayI2cBus;
using rtfuse::hal::replay::ReplayStream;

BusEvent can_send(std::uint8_t device, std::uint32_t id, std::uint8_t dlc, const std::uint8_t* data = nullptr) {
  BusEvent ev;
  ev.kind = BusEventKind::kCanSend;
  ev.device = device;
  ev.count = 1;
  ev.frames[0].id = id;
  ev.frames[0].dlc = dlc;
  for (int i = 0; i < dlc && data != nullptr; ++i) ev.frames[0].data[i] = data[i];
  return ev;
}

BusEvent i2c_read(std::uint8_t device, std::uint8_t addr, std::uint8_t reg, int len) {
  BusEvent ev;
  ev.kind = BusEventKind::kI2cRead;
  ev.device = device;
  ev.address = addr;
  ev.reg = reg;
  ev.length = len;
  for (int i = 0; i < len; ++i) ev.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  return ev;
}

CanFrame frame(std::uint32_t id, std::uint8_t dlc, std::uint8_t b0 = 0, std::uint8_t b1 = 0) {
  CanFrame f;
  f.id = id;
  f.dlc = dlc;
  f.data[0] = b0;
  f.data[1] = b1;
  return f;
}

TEST(HalReplayStream, ReportNamesTheEventTheRecordedAndTheAttemptedCall) {
  ReplayStream s("loop");
  s.append(can_send(0, 0x080, 0), 1233);
  s.append(can_send(0, 0x080, 0), 1234);
  ReplayCanBus bus(s, 0);
  EXPECT_EQ(bus.send(frame(0x080, 0)), HalStatus::kOk);
  EXPECT_EQ(bus.send(frame(0x000, 2, 0x01, 0x05)), HalStatus::kClosed);
  EXPECT_TRUE(s.diverged());
  EXPECT_EQ(s.divergence_kind(), DivergenceKind::kMismatch);
  EXPECT_STREQ(s.divergence(), "event 1234: recorded can_send id 0x080 dlc 0, driver sent id 0x000 dlc 2 [01 05]");
  EXPECT_EQ(s.divergence_event(), 1234);
  EXPECT_EQ(s.position(), 1u);
  EXPECT_EQ(s.remaining(), 1u);
  EXPECT_FALSE(s.at_end());
  // From then on the bus is gone, even for the call that was recorded.
  EXPECT_EQ(bus.send(frame(0x080, 0)), HalStatus::kClosed);
  EXPECT_STREQ(bus.last_error(), s.divergence());
  EXPECT_EQ(s.position(), 1u);
}

TEST(HalReplayStream, DataFlagsAndIdsAllCount) {
  const std::uint8_t data[2] = {0x01, 0x05};
  struct Case {
    CanFrame sent;
    const char* report;
  };
  CanFrame other_byte = frame(0x000, 2, 0x01, 0x06);
  CanFrame extended = frame(0x000, 2, 0x01, 0x05);
  extended.extended = true;
  CanFrame rtr = frame(0x000, 2, 0x01, 0x05);
  rtr.rtr = true;
  const Case cases[] = {
      {other_byte, "event 7: recorded can_send id 0x000 dlc 2 [01 05], driver sent id 0x000 dlc 2 [01 06]"},
      {extended, "event 7: recorded can_send id 0x000 dlc 2 [01 05], driver sent id 0x00000000 ext dlc 2 [01 05]"},
      {rtr, "event 7: recorded can_send id 0x000 dlc 2 [01 05], driver sent id 0x000 rtr dlc 2"},
  };
  for (const Case& c : cases) {
    ReplayStream s;
    s.append(can_send(0, 0x000, 2, data), 7);
    ReplayCanBus bus(s, 0);
    EXPECT_EQ(bus.send(c.sent), HalStatus::kClosed);
    EXPECT_STREQ(s.divergence(), c.report);
  }
  // Bytes past dlc and the stamp are not part of the call.
  ReplayStream s;
  s.append(can_send(0, 0x000, 2, data), 7);
  ReplayCanBus bus(s, 0);
  CanFrame same = frame(0x000, 2, 0x01, 0x05);
  same.data[5] = 0xFF;
  same.stamp = 99;
  EXPECT_EQ(bus.send(same), HalStatus::kOk);
  EXPECT_TRUE(s.at_end());
  EXPECT_FALSE(s.diverged());
}

TEST(HalReplayStream, ReceiveWhereASendWasRecorded) {
  ReplayStream s;
  s.append(can_send(0, 0x080, 0), 42);
  ReplayCanBus bus(s, 0);
  CanFrame out[4];
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(bus.receive(out, 4, 0, &st), 0);
  EXPECT_EQ(st, HalStatus::kClosed);
  EXPECT_STREQ(s.divergence(), "event 42: recorded can_send id 0x080 dlc 0, driver called can_receive max 4 timeout 0 ns");
}

TEST(HalReplayStream, I2cAddressRegisterLengthAndValueAreChecked) {
  struct Case {
    std::uint8_t addr;
    std::uint8_t reg;
    int len;
    const char* report;
  };
  const Case cases[] = {
      {0x69, 0x3B, 14, "event 10: recorded i2c_read addr 0x68 reg 0x3B len 14, driver called i2c_read addr 0x69 reg 0x3B len 14"},
      {0x68, 0x43, 14, "event 10: recorded i2c_read addr 0x68 reg 0x3B len 14, driver called i2c_read addr 0x68 reg 0x43 len 14"},
      {0x68, 0x3B, 6, "event 10: recorded i2c_read addr 0x68 reg 0x3B len 14, driver called i2c_read addr 0x68 reg 0x3B len 6"},
  };
  for (const Case& c : cases) {
    ReplayStream s;
    s.append(i2c_read(1, 0x68, 0x3B, 14), 10);
    ReplayI2cBus bus(s, 1);
    std::uint8_t buf[14] = {};
    EXPECT_EQ(bus.read_registers(c.addr, c.reg, buf, c.len), HalStatus::kClosed);
    EXPECT_EQ(buf[0], 0) << "nothing written on a divergence";
    EXPECT_STREQ(s.divergence(), c.report);
  }
  ReplayStream s;
  BusEvent w;
  w.kind = BusEventKind::kI2cWrite;
  w.device = 1;
  w.address = 0x68;
  w.reg = 0x6B;
  w.value = 0x01;
  w.length = 1;
  s.append(w, 3);
  ReplayI2cBus bus(s, 1);
  EXPECT_EQ(bus.write_register(0x68, 0x6B, 0x80), HalStatus::kClosed);
  EXPECT_STREQ(s.divergence(),
               "event 3: recorded i2c_write addr 0x68 reg 0x6B value 0x01, driver called i2c_write addr 0x68 reg 0x6B value 0x80");
}

TEST(HalReplayStream, ADifferentDeviceIsNamed) {
  ReplayStream s("imu");
  s.set_device_name(0, "can0");
  s.set_device_name(1, "can1");
  s.append(can_send(0, 0x080, 0), 5);
  ReplayCanBus bus1(s, 1);
  EXPECT_EQ(bus1.send(frame(0x080, 0)), HalStatus::kClosed);
  EXPECT_STREQ(s.divergence(), "event 5: recorded can_send on can0 id 0x080 dlc 0, driver sent on can1 id 0x080 dlc 0");
}

TEST(HalReplayStream, EndOfStreamIsACleanStopWithAReport) {
  ReplayStream s("imu");
  s.set_device_name(2, "imu-drdy");
  BusEvent edge;
  edge.kind = BusEventKind::kGpioWaitEdge;
  edge.device = 2;
  edge.timeout_ns = 10'000'000;
  edge.edge_stamp = 123'456;
  edge.level = 1;
  s.append(edge, 900);
  ReplayEdgeSource src(s, 2);
  GpioEdge e;
  ASSERT_EQ(src.wait_edge(10'000'000, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, 123'456);
  EXPECT_TRUE(e.rising);
  EXPECT_TRUE(s.at_end());
  EXPECT_FALSE(s.diverged());

  EXPECT_EQ(src.wait_edge(10'000'000, &e), HalStatus::kClosed);
  EXPECT_TRUE(s.diverged());
  EXPECT_EQ(s.divergence_kind(), DivergenceKind::kEndOfStream);
  EXPECT_TRUE(s.at_end()) << "running past the end is still a clean stop";
  EXPECT_EQ(s.divergence_event(), 900);
  EXPECT_STREQ(s.divergence(),
               "stream 'imu' ended after event 900 (1 events replayed): driver called gpio_wait_edge on imu-drdy "
               "timeout 10000000 ns");
}

TEST(HalReplayStream, AHoleInTheRecordingEndsTheStreamThereAndSaysWhy) {
  ReplayStream s("imu");
  s.append(i2c_read(0, 0x68, 0x3B, 2), 20);
  s.mark_hole(25, 3);
  ReplayI2cBus bus(s, 0);
  std::uint8_t b[2];
  ASSERT_EQ(bus.read_registers(0x68, 0x3B, b, 2), HalStatus::kOk);
  EXPECT_EQ(bus.read_registers(0x68, 0x3B, b, 2), HalStatus::kClosed);
  EXPECT_EQ(std::string(s.divergence()).rfind("stream 'imu' ends at event 25, where the recorder lost 3 events", 0), 0u)
      << s.divergence();
}

TEST(HalReplayStream, CompactedEventsExpandByteForByte) {
  ReplayStream s;
  BusEvent rx;
  rx.kind = BusEventKind::kCanReceive;
  rx.length = 16;
  rx.count = 3;
  for (int i = 0; i < 3; ++i) {
    rx.frames[i] = frame(0x181 + static_cast<std::uint32_t>(i), 8, static_cast<std::uint8_t>(i), 0xEE);
    rx.frames[i].stamp = 1000 * i + 7;
  }
  const BusEvent rd = i2c_read(0, 0x68, 0x3B, 14);
  s.append(rx, 1);
  s.append(rd, 2);
  s.append(can_send(0, 0x080, 0), 3);
  EXPECT_EQ(s.event(0), rx);
  EXPECT_EQ(s.event(1), rd);
  EXPECT_EQ(s.event(2), can_send(0, 0x080, 0));
  EXPECT_EQ(s.log_event(1), 2);
}

TEST(HalReplayStream, ClockAndOutputReplayTheRecordedValues) {
  ReplayStream s("imu");
  BusEvent now;
  now.kind = BusEventKind::kClockNow;
  now.clock_ns = 5'000;
  BusEvent sleep;
  sleep.kind = BusEventKind::kClockSleepUntil;
  sleep.clock_ns = 6'000;
  BusEvent set;
  set.kind = BusEventKind::kGpioSet;
  set.device = 1;
  set.level = 1;
  s.append(now, 1);
  s.append(sleep, 2);
  s.append(set, 3);
  now.clock_ns = 6'001;
  s.append(now, 4);
  s.append(sleep, 5);
  ReplayClock clock(s, 0);
  ReplayGpioOutput led(s, 1);
  EXPECT_EQ(clock.now(), 5'000);
  clock.sleep_until(6'000);
  EXPECT_EQ(led.set(true), HalStatus::kOk);
  EXPECT_TRUE(led.level());
  EXPECT_EQ(clock.now(), 6'001);
  clock.sleep_until(7'000);  // recorded 6'000
  EXPECT_TRUE(s.diverged());
  EXPECT_STREQ(s.divergence(),
               "event 5: recorded clock_sleep_until deadline 6000 ns, driver called clock_sleep_until deadline 7000 ns");
  EXPECT_EQ(clock.now(), 6'001) << "time stands still after a divergence";
}

TEST(HalReplayStream, ReplayCallsDoNotAllocate) {
  ReplayStream s;
  for (int i = 0; i < 50; ++i) {
    s.append(can_send(0, 0x080, 0), 2 * i);
    s.append(i2c_read(1, 0x68, 0x3B, 14), 2 * i + 1);
  }
  ReplayCanBus can(s, 0);
  ReplayI2cBus i2c(s, 1);
  std::uint8_t buf[14];
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 50; ++i) {
    EXPECT_EQ(can.send(frame(0x080, 0)), HalStatus::kOk);
    EXPECT_EQ(i2c.read_registers(0x68, 0x3B, buf, 14), HalStatus::kOk);
  }
  EXPECT_EQ(can.send(frame(0x080, 0)), HalStatus::kClosed);  // past the end: the report is built in place
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(buf[13], 0xA0 + 13);
}

}  // namespace replay_stream_test
