// A serial port recorded and replayed: the events hold what the driver got
// (bytes, their stamp, the status), and the replay port hands the same back
// or reports where the driver's calls differ.
#include "hal/recording_serial_port.hpp"

#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hal/mock/mock_serial_port.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/replay/replay_serial_port.hpp"
#include "hal/replay/replay_stream.hpp"
#include "support/alloc_counter.hpp"

namespace recording_serial_port_test {

using rtfuse::SpscRing;
using rtfuse::TimeNs;
using rtfuse::hal::BusEvent;
using rtfuse::hal::BusEventKind;
using rtfuse::hal::HalStatus;
using rtfuse::hal::kBusEventMaxBytes;
using rtfuse::hal::RecordingSerialPort;
using rtfuse::hal::mock::MockSerialPort;
using rtfuse::hal::mock::SimClock;
using rtfuse::hal::replay::ReplaySerialPort;
using rtfuse::hal::replay::ReplayStream;

std::vector<std::uint8_t> bytes(int n, int seed) {
  std::vector<std::uint8_t> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(seed + 7 * i);
  return v;
}

struct Rig {
  BusEvent pop() {
    BusEvent ev;
    EXPECT_TRUE(ring.try_pop(ev));
    return ev;
  }
  SimClock clock{1'000};
  MockSerialPort port{clock};
  SpscRing<BusEvent> ring{64};
  RecordingSerialPort rec{port, ring, 3, &clock};
};

TEST(HalRecordingSerialPort, AReadTakesAtMostOneEventsBytesAndRecordsThemWithTheirStamp) {
  Rig r;
  const std::vector<std::uint8_t> in = bytes(100, 1);
  ASSERT_TRUE(r.port.feed(in.data(), 100, 5'000));
  r.clock.set(6'000);
  std::uint8_t buf[512];
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kClosed;
  ASSERT_EQ(r.rec.read(buf, sizeof buf, 0, &stamp, &st), kBusEventMaxBytes);
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(stamp, 5'000);
  EXPECT_EQ(std::memcmp(buf, in.data(), kBusEventMaxBytes), 0);
  ASSERT_EQ(r.rec.read(buf, sizeof buf, 0, &stamp, &st), 36);
  EXPECT_EQ(std::memcmp(buf, in.data() + 64, 36), 0);
  EXPECT_EQ(r.rec.read(buf, sizeof buf, 0, &stamp, &st), 0);
  EXPECT_EQ(st, HalStatus::kWouldBlock);
  EXPECT_EQ(stamp, 0);

  const BusEvent a = r.pop();
  EXPECT_EQ(a.kind, BusEventKind::kSerialRead);
  EXPECT_EQ(a.device, 3);
  EXPECT_EQ(a.time_ns, 6'000);
  EXPECT_EQ(a.length, kBusEventMaxBytes);  // 512 asked, capped
  EXPECT_EQ(a.count, kBusEventMaxBytes);
  EXPECT_EQ(a.edge_stamp, 5'000);
  EXPECT_EQ(std::memcmp(a.data, in.data(), 64), 0);
  const BusEvent b = r.pop();
  EXPECT_EQ(b.count, 36);
  const BusEvent c = r.pop();
  EXPECT_EQ(c.count, 0);
  EXPECT_EQ(c.status, HalStatus::kWouldBlock);
  EXPECT_EQ(c.edge_stamp, 0);
  EXPECT_EQ(c.data[0], 0);  // canonical: unused bytes zero
}

TEST(HalRecordingSerialPort, ALongWriteGoesOutAndIsRecordedInPieces) {
  Rig r;
  const std::vector<std::uint8_t> out = bytes(150, 9);
  ASSERT_EQ(r.rec.write(out.data(), 150), HalStatus::kOk);
  ASSERT_EQ(r.port.written_size(), 150);
  EXPECT_EQ(std::memcmp(r.port.written(), out.data(), 150), 0);
  int total = 0;
  for (int expect : {64, 64, 22}) {
    const BusEvent w = r.pop();
    EXPECT_EQ(w.kind, BusEventKind::kSerialWrite);
    EXPECT_EQ(w.length, expect);
    EXPECT_EQ(std::memcmp(w.data, out.data() + total, static_cast<std::size_t>(expect)), 0);
    total += expect;
  }
}

TEST(HalRecordingSerialPort, AnUnpluggedPortIsRecordedAsClosed) {
  Rig r;
  r.port.unplug();
  std::uint8_t buf[16];
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(r.rec.read(buf, 16, 1'000'000, &stamp, &st), 0);
  EXPECT_EQ(st, HalStatus::kClosed);
  const BusEvent ev = r.pop();
  EXPECT_EQ(ev.status, HalStatus::kClosed);
  EXPECT_EQ(ev.timeout_ns, 1'000'000);
  EXPECT_EQ(ev.length, 16);
}

TEST(HalRecordingSerialPort, ReopensAreRecordedAndReplayedWithTheirOutcome) {
  Rig r;
  r.port.unplug();
  EXPECT_FALSE(r.rec.reopen());
  r.port.replug();
  EXPECT_TRUE(r.rec.reopen());
  ReplayStream stream("gnss");
  BusEvent ev;
  std::int64_t n = 0;
  while (r.ring.try_pop(ev)) {
    EXPECT_EQ(ev.kind, BusEventKind::kSerialReopen);
    stream.append(ev, ++n);
  }
  ASSERT_EQ(n, 2);
  ReplaySerialPort port(stream, 3);
  EXPECT_FALSE(port.reopen());
  EXPECT_TRUE(port.reopen());
  EXPECT_TRUE(stream.at_end());
}

// Records a session, loads it into a stream as rtfuse-replay would.
struct Recorded {
  Recorded() {
    Rig r;
    const std::vector<std::uint8_t> in = bytes(90, 3);
    r.port.feed(in.data(), 90, 2'000);
    r.clock.set(3'000);
    std::uint8_t buf[128];
    TimeNs stamp;
    HalStatus st;
    r.rec.read(buf, 128, 50'000'000, &stamp, &st);
    r.rec.read(buf, 128, 50'000'000, &stamp, &st);
    const std::vector<std::uint8_t> cmd = bytes(70, 40);
    r.rec.write(cmd.data(), 70);
    r.rec.read(buf, 128, 50'000'000, &stamp, &st);  // times out on the clock
    BusEvent ev;
    std::int64_t n = 0;
    while (r.ring.try_pop(ev)) {
      events.push_back(ev);
      stream.append(ev, ++n);
    }
    stream.set_device_name(3, "gnss0");
    input = in;
    command = cmd;
  }
  ReplayStream stream{"gnss"};
  std::vector<BusEvent> events;
  std::vector<std::uint8_t> input;
  std::vector<std::uint8_t> command;
};

TEST(HalReplaySerialPort, GivesBackTheRecordedBytesStampsAndStatuses) {
  Recorded rec;
  ASSERT_EQ(rec.events.size(), 5u);  // 2 reads, a write in 2 pieces, a timeout
  ReplaySerialPort port(rec.stream, 3);
  std::uint8_t buf[128];
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kClosed;
  rtfuse::test::AllocScope scope;
  ASSERT_EQ(port.read(buf, 128, 50'000'000, &stamp, &st), 64);
  EXPECT_EQ(stamp, 2'000);
  EXPECT_EQ(std::memcmp(buf, rec.input.data(), 64), 0);
  ASSERT_EQ(port.read(buf, 128, 50'000'000, &stamp, &st), 26);
  EXPECT_EQ(std::memcmp(buf, rec.input.data() + 64, 26), 0);
  EXPECT_EQ(port.write(rec.command.data(), 70), HalStatus::kOk);
  EXPECT_EQ(port.read(buf, 128, 50'000'000, &stamp, &st), 0);
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_TRUE(rec.stream.at_end());
  EXPECT_FALSE(rec.stream.diverged());
}

TEST(HalReplaySerialPort, AnotherTimeoutIsADivergenceNamingBothCalls) {
  Recorded rec;
  ReplaySerialPort port(rec.stream, 3);
  std::uint8_t buf[128];
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(port.read(buf, 128, 10'000'000, &stamp, &st), 0);
  EXPECT_EQ(st, HalStatus::kClosed);
  ASSERT_TRUE(rec.stream.diverged());
  const std::string report = port.last_error();
  EXPECT_NE(report.find("recorded serial_read max 64 timeout 50000000 ns"), std::string::npos) << report;
  EXPECT_NE(report.find("driver called serial_read max 64 timeout 10000000 ns"), std::string::npos) << report;
}

TEST(HalReplaySerialPort, OtherBytesWrittenAreADivergenceShowingThem) {
  Recorded rec;
  ReplaySerialPort port(rec.stream, 3);
  std::uint8_t buf[128];
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  port.read(buf, 128, 50'000'000, &stamp, &st);
  port.read(buf, 128, 50'000'000, &stamp, &st);
  std::vector<std::uint8_t> other = rec.command;
  other[66] ^= 0xFF;  // in the second piece
  EXPECT_EQ(port.write(other.data(), 70), HalStatus::kClosed);
  const std::string report = port.last_error();
  EXPECT_NE(report.find("recorded serial_write 6 bytes"), std::string::npos) << report;
  EXPECT_NE(report.find("driver called serial_write 6 bytes"), std::string::npos) << report;
}

}  // namespace recording_serial_port_test
