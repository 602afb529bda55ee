#include "hal/mock/mock_serial_port.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hal/mock/sim_clock.hpp"

#include "support/alloc_counter.hpp"

namespace mock_serial_port_test {

using rtfuse::TimeNs;
using rtfuse::hal::HalStatus;
using rtfuse::hal::mock::MockSerialPort;
using rtfuse::hal::mock::MockSerialPortCapacity;
using rtfuse::hal::mock::SimClock;

constexpr TimeNs kMs = 1'000'000;

std::vector<std::uint8_t> bytes(const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); }

bool feed(MockSerialPort& port, const std::string& s, TimeNs arrival) {
  const std::vector<std::uint8_t> b = bytes(s);
  return port.feed(b.data(), static_cast<int>(b.size()), arrival);
}

// Reads what is due now; the bytes as a string.
std::string read_now(MockSerialPort& port, int max, TimeNs* stamp, HalStatus* st, TimeNs timeout = 0) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(max));
  const int n = port.read(buf.data(), max, timeout, stamp, st);
  return std::string(buf.begin(), buf.begin() + (n > 0 ? n : 0));
}

// A clock that never moves, like a replay clock after a divergence.
class StuckClock final : public rtfuse::hal::Clock {
 public:
  TimeNs now() const noexcept override { return 7 * kMs; }
  void sleep_until(TimeNs) noexcept override {}
};

TEST(HalMockSerialPort, BytesComeOutOnlyOnceTheClockReachesTheirArrival) {
  SimClock clock(0);
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "$GP", 10 * kMs));
  ASSERT_TRUE(feed(port, "GGA", 20 * kMs));
  EXPECT_EQ(port.pending(), 6);

  TimeNs stamp = -1;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "");
  EXPECT_EQ(st, HalStatus::kWouldBlock);
  EXPECT_EQ(stamp, -1);
  EXPECT_EQ(clock.now(), 0);  // timeout 0 never moves time

  clock.set(15 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "$GP");
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(stamp, 10 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "");
  EXPECT_EQ(st, HalStatus::kWouldBlock);

  clock.set(20 * kMs);  // due exactly now
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "GGA");
  EXPECT_EQ(stamp, 20 * kMs);
  EXPECT_EQ(port.pending(), 0);
}

TEST(HalMockSerialPort, AWaitingReadSleepsToTheNextArrivalWithinTheTimeout) {
  SimClock clock(100 * kMs);
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "\xb5\x62", 130 * kMs));
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  // Due beyond a 20 ms wait: time stops at the deadline, nothing comes.
  EXPECT_EQ(read_now(port, 16, &stamp, &st, 20 * kMs), "");
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), 120 * kMs);
  // Within a 50 ms wait: time stops at the arrival.
  EXPECT_EQ(read_now(port, 16, &stamp, &st, 50 * kMs), "\xb5\x62");
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(stamp, 130 * kMs);
  EXPECT_EQ(clock.now(), 130 * kMs);
  // Nothing fed at all: the whole timeout passes.
  EXPECT_EQ(read_now(port, 16, &stamp, &st, 40 * kMs), "");
  EXPECT_EQ(st, HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), 170 * kMs);
}

TEST(HalMockSerialPort, OneReadTakesEveryDueArrivalStampedWithTheFirstByte) {
  SimClock clock(0);
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "abc", 1 * kMs));
  ASSERT_TRUE(feed(port, "de", 2 * kMs));
  ASSERT_TRUE(feed(port, "f", 9 * kMs));
  clock.set(5 * kMs);
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 2, &stamp, &st), "ab");  // max respected
  EXPECT_EQ(stamp, 1 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "cde");  // not "f": still on the wire
  EXPECT_EQ(stamp, 1 * kMs);                          // "c" came at 1 ms
  clock.set(9 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "f");
  EXPECT_EQ(stamp, 9 * kMs);
}

TEST(HalMockSerialPort, AnArrivalBeforeTheLastIsTakenAsTheLast) {
  SimClock clock(0);
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "a", 10 * kMs));
  ASSERT_TRUE(feed(port, "b", 4 * kMs));
  clock.set(6 * kMs);
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "");  // "b" waits behind "a", as on a wire
  clock.set(10 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "ab");
  EXPECT_EQ(stamp, 10 * kMs);
}

TEST(HalMockSerialPort, AFullQueueDropsAndCountsTheOverrun) {
  SimClock clock(0);
  MockSerialPort port(clock, MockSerialPortCapacity{8, 16});
  ASSERT_TRUE(feed(port, "12345", 1 * kMs));
  EXPECT_FALSE(feed(port, "67890", 2 * kMs));  // 3 fit, 2 dropped
  EXPECT_EQ(port.pending(), 8);
  EXPECT_EQ(port.overruns(), 1);
  EXPECT_EQ(port.dropped_bytes(), 2);
  EXPECT_FALSE(feed(port, "x", 3 * kMs));
  EXPECT_EQ(port.overruns(), 2);
  EXPECT_EQ(port.dropped_bytes(), 3);

  clock.set(3 * kMs);
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "12345678");
  // Room again, and the ring wraps without mixing up bytes.
  ASSERT_TRUE(feed(port, "abcdefgh", 4 * kMs));
  clock.set(4 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "abcdefgh");
  EXPECT_EQ(stamp, 4 * kMs);
  EXPECT_EQ(port.overruns(), 2);
}

TEST(HalMockSerialPort, UnpluggedReadsAndWritesAreClosedUntilReplug) {
  SimClock clock(0);
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "lost", 1 * kMs));
  port.unplug();
  EXPECT_TRUE(port.unplugged());
  EXPECT_EQ(port.pending(), 0);  // gone with the device
  clock.set(2 * kMs);
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 16, &stamp, &st, 10 * kMs), "");
  EXPECT_EQ(st, HalStatus::kClosed);
  EXPECT_EQ(clock.now(), 2 * kMs);  // no wait on a closed port
  EXPECT_NE(std::string(port.last_error()).find("unplugged"), std::string::npos);
  const std::uint8_t poll_msg[] = {0xb5, 0x62, 0x06, 0x01};
  EXPECT_EQ(port.write(poll_msg, 4), HalStatus::kClosed);
  EXPECT_EQ(port.written_size(), 0);
  EXPECT_FALSE(feed(port, "also lost", 3 * kMs));
  EXPECT_EQ(port.overruns(), 0);  // not an overrun: nothing was there to receive

  port.replug();
  EXPECT_FALSE(port.unplugged());
  ASSERT_TRUE(feed(port, "back", 4 * kMs));
  clock.set(4 * kMs);
  EXPECT_EQ(read_now(port, 16, &stamp, &st), "back");
  EXPECT_EQ(st, HalStatus::kOk);
  EXPECT_EQ(port.write(poll_msg, 4), HalStatus::kOk);
}

TEST(HalMockSerialPort, WritesAreKeptInOrderAndAFullLogTimesOut) {
  SimClock clock(0);
  MockSerialPort port(clock, MockSerialPortCapacity{16, 8});
  const std::uint8_t a[] = {0xb5, 0x62, 0x06, 0x8a, 0x0a};
  const std::uint8_t b[] = {0x11, 0x13, 0x00};
  ASSERT_EQ(port.write(a, 5), HalStatus::kOk);
  ASSERT_EQ(port.write(b, 3), HalStatus::kOk);
  ASSERT_EQ(port.written_size(), 8);
  EXPECT_EQ(std::vector<std::uint8_t>(port.written(), port.written() + 8),
            (std::vector<std::uint8_t>{0xb5, 0x62, 0x06, 0x8a, 0x0a, 0x11, 0x13, 0x00}));
  EXPECT_EQ(port.write(b, 1), HalStatus::kTimeout);  // all or nothing
  EXPECT_EQ(port.written_size(), 8);
  EXPECT_EQ(port.write(b, 0), HalStatus::kOk);
  port.clear_written();
  EXPECT_EQ(port.written_size(), 0);
  ASSERT_EQ(port.write(b, 3), HalStatus::kOk);
  EXPECT_EQ(port.written()[0], 0x11);
}

TEST(HalMockSerialPort, AClockThatDoesNotMoveTimesOutInsteadOfSpinning) {
  StuckClock clock;
  MockSerialPort port(clock);
  ASSERT_TRUE(feed(port, "later", 50 * kMs));
  TimeNs stamp = 0;
  HalStatus st = HalStatus::kOk;
  EXPECT_EQ(read_now(port, 16, &stamp, &st, 100 * kMs), "");
  EXPECT_EQ(st, HalStatus::kTimeout);
}

TEST(HalMockSerialPort, ReadWriteAndFeedDoNotAllocate) {
  SimClock clock(0);
  MockSerialPort port(clock, MockSerialPortCapacity{256, 64});
  const std::uint8_t sentence[] = "$GNGSA,A,3,,,,,,,,,,,,,1.0,1.0,1.0*00\r\n";
  const int len = static_cast<int>(sizeof sentence - 1);
  std::uint8_t buf[64];
  TimeNs stamp = 0;
  HalStatus st{};
  int received = 0;
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 200; ++i) {
      port.feed(sentence, len, (i + 1) * 100 * kMs);
      received += port.read(buf, sizeof buf, 200 * kMs, &stamp, &st);
      (void)port.read(buf, sizeof buf, 0, &stamp, &st);
      if (port.write(sentence, 8) != HalStatus::kOk) port.clear_written();
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(received, 200 * len);
  EXPECT_EQ(clock.now(), 200 * 100 * kMs);
}

}  // namespace mock_serial_port_test
