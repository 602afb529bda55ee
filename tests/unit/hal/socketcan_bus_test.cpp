// SocketCAN backend. The machines here have no AF_CAN, so open() is tested
// on its real failure path, and the frame handling through an AF_UNIX
// SOCK_SEQPACKET pair: each record is one struct can_frame, as a CAN_RAW
// socket delivers it. AF_UNIX honours SO_TIMESTAMPNS/SO_TIMESTAMP on the
// receiving end and stamps the record when it is queued (checked below by
// reading 30 ms after sending), so the kernel-timestamp path runs for real.
#include "hal/linux/socketcan_bus.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include "support/alloc_counter.hpp"

namespace socketcan_bus_test {

using rtfuse::TimeNs;
using rtfuse::monotonic_now_ns;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::CanIdFilter;
using rtfuse::hal::HalStatus;
using rtfuse::hal::SocketCanBus;

constexpr TimeNs kMs = 1'000'000;

bool has_substr(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

can_frame make_kernel_frame(canid_t id, std::uint8_t dlc, std::uint8_t first_byte = 0) {
  can_frame cf;
  std::memset(&cf, 0, sizeof cf);
  cf.can_id = id;
  cf.can_dlc = dlc;
  for (int i = 0; i < CAN_MAX_DLEN; ++i) cf.data[i] = static_cast<std::uint8_t>(first_byte + i);
  return cf;
}

can_frame make_error_frame(canid_t err_class, std::uint8_t ctrl = 0) {
  can_frame cf = make_kernel_frame(CAN_ERR_FLAG | err_class, CAN_ERR_DLC);
  std::memset(cf.data, 0, sizeof cf.data);
  cf.data[1] = ctrl;
  return cf;
}

class SocketCanPair : public ::testing::Test {
 protected:
  // The bus owns sv[0]; the test plays the kernel on sv[1].
  void make_bus(int timestamp_option) {
    bus_.reset();
    if (peer_ >= 0) ::close(peer_);
    peer_ = -1;
    int sv[2];
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sv), 0) << std::strerror(errno);
    if (timestamp_option != 0) {
      const int on = 1;
      ASSERT_EQ(setsockopt(sv[0], SOL_SOCKET, timestamp_option, &on, sizeof on), 0) << std::strerror(errno);
    }
    peer_ = sv[1];
    bus_ = SocketCanBus::adopt(sv[0], "pair0");
    ASSERT_NE(bus_, nullptr);
  }
  // SO_TIMESTAMPNS is in every kernel rtfuse runs on (2.6.22+), but qemu-user
  // 7.2 does not translate it and refuses it with ENOPROTOOPT.
  static bool option_available(int option) {
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sv) != 0) return false;
    const int on = 1;
    const bool ok = setsockopt(sv[0], SOL_SOCKET, option, &on, sizeof on) == 0 || errno != ENOPROTOOPT;
    ::close(sv[0]);
    ::close(sv[1]);
    return ok;
  }
  void SetUp() override { make_bus(0); }
  void TearDown() override {
    if (peer_ >= 0) ::close(peer_);
  }
  void put_bytes(const void* p, std::size_t n) {
    ASSERT_EQ(::send(peer_, p, n, MSG_DONTWAIT), static_cast<ssize_t>(n)) << std::strerror(errno);
  }
  void put(const can_frame& cf) { put_bytes(&cf, sizeof cf); }
  // The record the bus sent, or size -1 when none is queued.
  ssize_t take(can_frame* cf) { return ::recv(peer_, cf, sizeof *cf, MSG_DONTWAIT); }

  std::unique_ptr<SocketCanBus> bus_;
  int peer_ = -1;
};

TEST(HalSocketCanOpen, FailsWithoutAfCanNamingModulesAndErrno) {
  const int probe = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe >= 0) {
    ::close(probe);
    GTEST_SKIP() << "this kernel has AF_CAN; the failure path needs a machine without it";
  }
  ASSERT_EQ(errno, EAFNOSUPPORT);
  std::string error;
  const CanIdFilter filters[] = {{0x181, 0x7FF, false}, {0x18FF0001, 0x1FFFFFFF, true}};
  auto bus = SocketCanBus::open("can0", filters, 2, &error);
  EXPECT_EQ(bus, nullptr);
  EXPECT_TRUE(has_substr(error, "'can0'")) << error;
  EXPECT_TRUE(has_substr(error, "socket(PF_CAN, SOCK_RAW, CAN_RAW)")) << error;
  EXPECT_TRUE(has_substr(error, "Address family not supported by protocol")) << error;
  EXPECT_TRUE(has_substr(error, "modprobe can can_raw")) << error;
  EXPECT_TRUE(has_substr(error, "CONFIG_CAN_RAW")) << error;

  // No error string wanted: still a clean nullptr.
  EXPECT_EQ(SocketCanBus::open("can0", nullptr, 0, nullptr), nullptr);
}

TEST(HalSocketCanOpen, RejectsBadArgumentsBeforeTouchingTheKernel) {
  std::string error;
  EXPECT_EQ(SocketCanBus::open("", nullptr, 0, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "1..15 characters")) << error;
  EXPECT_EQ(SocketCanBus::open("a_name_longer_than_ifnamsiz", nullptr, 0, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "a_name_longer_than_ifnamsiz")) << error;

  EXPECT_EQ(SocketCanBus::open("can0", nullptr, 3, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "3 ID filters")) << error;
  EXPECT_EQ(SocketCanBus::open("can0", nullptr, -1, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "512")) << error;

  const CanIdFilter too_wide{0x800, 0x7FF, false};
  EXPECT_EQ(SocketCanBus::open("can0", &too_wide, 1, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "id 0x800 does not fit in 11 bits")) << error;
  EXPECT_TRUE(has_substr(error, "set extended")) << error;
  const CanIdFilter too_wide_ext{0x20000000, 0, true};
  EXPECT_EQ(SocketCanBus::open("can0", &too_wide_ext, 1, &error), nullptr);
  EXPECT_TRUE(has_substr(error, "29 bits")) << error;
}

// Failures this machine cannot produce for real: the advice text per errno.
TEST(HalSocketCanOpen, MessagesGiveTheLikelyFix) {
  using rtfuse::hal::socketcan_detail::open_error_message;
  const std::string no_dev = open_error_message("can0", "ioctl(SIOCGIFINDEX)", ENODEV);
  EXPECT_TRUE(has_substr(no_dev, "ioctl(SIOCGIFINDEX) failed: No such device")) << no_dev;
  EXPECT_TRUE(has_substr(no_dev, "no interface 'can0': check `ip link`")) << no_dev;
  EXPECT_TRUE(has_substr(no_dev, "ip link set can0 up type can bitrate 500000")) << no_dev;
  EXPECT_TRUE(has_substr(no_dev, "modprobe vcan; ip link add dev vcan0 type vcan")) << no_dev;

  const std::string not_can = open_error_message("eth0", "bind", ENODEV);
  EXPECT_TRUE(has_substr(not_can, "'eth0' is not a CAN interface")) << not_can;

  const std::string down = open_error_message("can1", "interface up check (SIOCGIFFLAGS)", ENETDOWN);
  EXPECT_TRUE(has_substr(down, "Network is down")) << down;
  EXPECT_TRUE(has_substr(down, "ip link set can1 up type can bitrate 500000")) << down;

  const std::string no_raw = open_error_message("can0", "socket(PF_CAN, SOCK_RAW, CAN_RAW)", EPROTONOSUPPORT);
  EXPECT_TRUE(has_substr(no_raw, "modprobe can_raw")) << no_raw;

  const std::string other = open_error_message("can0", "bind", EADDRINUSE);
  EXPECT_TRUE(has_substr(other, "Address already in use")) << other;
  EXPECT_TRUE(has_substr(other, "ip -details link show can0")) << other;
}

TEST(HalSocketCanAdopt, RejectsNegativeFd) { EXPECT_EQ(SocketCanBus::adopt(-1, "none"), nullptr); }

TEST_F(SocketCanPair, FramesRoundTripThroughThePeer) {
  CanFrame sent[4];
  sent[0].id = 0x181;
  sent[0].dlc = 8;
  for (int i = 0; i < 8; ++i) sent[0].data[i] = static_cast<std::uint8_t>(0xA0 + i);
  sent[1].id = 0x18FF0001;
  sent[1].extended = true;
  sent[1].dlc = 3;
  sent[1].data[0] = 1;
  sent[1].data[1] = 2;
  sent[1].data[2] = 3;
  sent[2].id = 0x701;
  sent[2].rtr = true;
  sent[2].dlc = 1;
  sent[3].id = 0x000;
  sent[3].dlc = 0;

  for (const CanFrame& f : sent) {
    ASSERT_EQ(bus_->send(f), HalStatus::kOk) << bus_->last_error();
    can_frame cf;
    ASSERT_EQ(take(&cf), static_cast<ssize_t>(sizeof cf));
    put(cf);  // echo, as a loopback-enabled bus would
  }
  CanFrame got[8];
  HalStatus status = HalStatus::kIoError;
  ASSERT_EQ(bus_->receive(got, 8, 0, &status), 4);
  EXPECT_EQ(status, HalStatus::kOk);
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(got[k].id, sent[k].id);
    EXPECT_EQ(got[k].extended, sent[k].extended);
    EXPECT_EQ(got[k].rtr, sent[k].rtr);
    EXPECT_FALSE(got[k].error);
    EXPECT_EQ(got[k].dlc, sent[k].dlc);
    EXPECT_EQ(std::memcmp(got[k].data, sent[k].data, sent[k].dlc), 0);
    EXPECT_GT(got[k].stamp, 0);
  }
  EXPECT_EQ(bus_->malformed(), 0);
  EXPECT_EQ(bus_->state(), CanBusState::kUnknown);
}

TEST_F(SocketCanPair, ReceivedFlagsAndIdsAreDecoded) {
  put(make_kernel_frame(0x7FF, 2, 0x10));
  put(make_kernel_frame(CAN_EFF_FLAG | 0x1FFFFFFF, 8, 0x20));
  put(make_kernel_frame(CAN_EFF_FLAG | CAN_RTR_FLAG | 0x123, 4));
  CanFrame got[3];
  HalStatus status{};
  ASSERT_EQ(bus_->receive(got, 3, 0, &status), 3);
  EXPECT_EQ(got[0].id, 0x7FFU);
  EXPECT_FALSE(got[0].extended);
  EXPECT_EQ(got[0].dlc, 2);
  EXPECT_EQ(got[0].data[0], 0x10);
  EXPECT_EQ(got[0].data[1], 0x11);
  EXPECT_EQ(got[0].data[2], 0) << "bytes past dlc are cleared";
  EXPECT_EQ(got[1].id, 0x1FFFFFFFU);
  EXPECT_TRUE(got[1].extended);
  EXPECT_EQ(got[1].data[7], 0x27);
  EXPECT_EQ(got[2].id, 0x123U);
  EXPECT_TRUE(got[2].extended);
  EXPECT_TRUE(got[2].rtr);
  EXPECT_EQ(got[2].dlc, 4);
}

TEST_F(SocketCanPair, KernelTimestampIsConvertedToMonotonic) {
  if (!option_available(SO_TIMESTAMPNS)) GTEST_SKIP() << "SO_TIMESTAMPNS refused (ENOPROTOOPT): qemu-user?";
  ASSERT_NO_FATAL_FAILURE(make_bus(SO_TIMESTAMPNS));
  const TimeNs before_send = monotonic_now_ns();
  put(make_kernel_frame(0x100, 1));
  const TimeNs after_send = monotonic_now_ns();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  CanFrame f;
  HalStatus status{};
  ASSERT_EQ(bus_->receive(&f, 1, 0, &status), 1);
  const TimeNs read_done = monotonic_now_ns();
  // The stamp is the queueing time (kernel, realtime converted), not the
  // read time 30 ms later: only the SCM_TIMESTAMPNS path can give that.
  EXPECT_GE(f.stamp, before_send - 2 * kMs);
  EXPECT_LE(f.stamp, after_send + 2 * kMs);
  EXPECT_GE(read_done - f.stamp, 25 * kMs);
}

TEST_F(SocketCanPair, MicrosecondTimestampIsUsedToo) {
  ASSERT_NO_FATAL_FAILURE(make_bus(SO_TIMESTAMP));
  const TimeNs before_send = monotonic_now_ns();
  put(make_kernel_frame(0x100, 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  CanFrame f;
  HalStatus status{};
  ASSERT_EQ(bus_->receive(&f, 1, 0, &status), 1);
  EXPECT_GE(f.stamp, before_send - 2 * kMs);
  EXPECT_LE(f.stamp, before_send + 10 * kMs);
}

TEST_F(SocketCanPair, WithoutKernelStampTheReadTimeIsUsed) {
  put(make_kernel_frame(0x100, 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const TimeNs before = monotonic_now_ns();
  CanFrame f;
  HalStatus status{};
  ASSERT_EQ(bus_->receive(&f, 1, 0, &status), 1);
  const TimeNs after = monotonic_now_ns();
  EXPECT_GE(f.stamp, before);
  EXPECT_LE(f.stamp, after);
}

TEST_F(SocketCanPair, WrongSizeAndBadDlcRecordsAreSkippedAndCounted) {
  const unsigned char short_record[10] = {1, 2, 3};
  put_bytes(short_record, sizeof short_record);
  put(make_kernel_frame(0x100, 9));
  unsigned char long_record[200] = {};
  put_bytes(long_record, sizeof long_record);

  CanFrame f[4];
  HalStatus status{};
  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kMalformed);
  EXPECT_EQ(bus_->malformed(), 3);

  // Bad records between good ones cost nothing but the count.
  put(make_kernel_frame(0x101, 1));
  put_bytes(short_record, sizeof short_record);
  put(make_kernel_frame(0x102, 15));
  put(make_kernel_frame(0x103, 2));
  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 2);
  EXPECT_EQ(status, HalStatus::kOk);
  EXPECT_EQ(f[0].id, 0x101U);
  EXPECT_EQ(f[1].id, 0x103U);
  EXPECT_EQ(bus_->malformed(), 5);

  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kWouldBlock);
}

TEST_F(SocketCanPair, ErrorFramesMoveStateAndAreReturned) {
  EXPECT_EQ(bus_->state(), CanBusState::kUnknown);
  CanFrame f;
  HalStatus status{};
  struct Step {
    can_frame frame;
    CanBusState expected;
  };
  const Step steps[] = {
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING), CanBusState::kErrorWarning},
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE), CanBusState::kErrorPassive},
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW), CanBusState::kErrorPassive},
      {make_error_frame(CAN_ERR_BUSOFF), CanBusState::kBusOff},
      {make_error_frame(CAN_ERR_RESTARTED), CanBusState::kErrorActive},
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE), CanBusState::kErrorPassive},
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE), CanBusState::kErrorActive},
      {make_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING), CanBusState::kErrorWarning},
      {make_error_frame(CAN_ERR_PROT | CAN_ERR_BUSOFF), CanBusState::kBusOff},
  };
  for (const Step& s : steps) {
    SCOPED_TRACE(s.frame.can_id);
    put(s.frame);
    ASSERT_EQ(bus_->receive(&f, 1, 0, &status), 1);
    EXPECT_EQ(status, HalStatus::kOk);
    EXPECT_TRUE(f.error);
    EXPECT_FALSE(f.extended);
    EXPECT_FALSE(f.rtr);
    EXPECT_EQ(f.id, s.frame.can_id & CAN_ERR_MASK);
    EXPECT_EQ(f.dlc, CAN_ERR_DLC);
    EXPECT_EQ(f.data[1], s.frame.data[1]);
    EXPECT_EQ(bus_->state(), s.expected);
  }
}

TEST_F(SocketCanPair, TimeoutWhenNothingComes) {
  CanFrame f;
  HalStatus status{};
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(bus_->receive(&f, 1, 50 * kMs, &status), 0);
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(status, HalStatus::kTimeout);
  EXPECT_GE(waited, std::chrono::milliseconds(50));
  EXPECT_LT(waited, std::chrono::milliseconds(500));

  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_EQ(bus_->receive(&f, 1, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kWouldBlock);
  EXPECT_LT(std::chrono::steady_clock::now() - t1, std::chrono::milliseconds(20));
}

TEST_F(SocketCanPair, TimeoutWakesOnTheFirstFrame) {
  const can_frame cf = make_kernel_frame(0x321, 1);
  std::thread writer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ::send(peer_, &cf, sizeof cf, 0);
  });
  CanFrame f;
  HalStatus status{};
  const auto t0 = std::chrono::steady_clock::now();
  const int n = bus_->receive(&f, 1, 5000 * kMs, &status);
  const auto waited = std::chrono::steady_clock::now() - t0;
  writer.join();
  ASSERT_EQ(n, 1);
  EXPECT_EQ(status, HalStatus::kOk);
  EXPECT_EQ(f.id, 0x321U);
  EXPECT_LT(waited, std::chrono::milliseconds(2000));
}

TEST_F(SocketCanPair, MaxIsRespectedAndOrderKept) {
  for (std::uint32_t i = 0; i < 10; ++i) put(make_kernel_frame(0x200 + i, 1));
  CanFrame f[8];
  HalStatus status{};
  const int expected[] = {4, 4, 2};
  std::uint32_t next = 0x200;
  for (int batch : expected) {
    ASSERT_EQ(bus_->receive(f, 4, 100 * kMs, &status), batch);
    EXPECT_EQ(status, HalStatus::kOk);
    for (int k = 0; k < batch; ++k) EXPECT_EQ(f[k].id, next++);
  }
  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kWouldBlock);
  EXPECT_EQ(bus_->receive(f, 0, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kOk);
}

TEST_F(SocketCanPair, SendWritesTheExactKernelStruct) {
  CanFrame std_frame;
  std_frame.id = 0x080;
  std_frame.dlc = 0;
  CanFrame ext;
  ext.id = 0x1ABCDEF0;
  ext.extended = true;
  ext.dlc = 5;
  for (int i = 0; i < 8; ++i) ext.data[i] = static_cast<std::uint8_t>(0x50 + i);
  CanFrame rtr;
  rtr.id = 0x705;
  rtr.rtr = true;
  rtr.dlc = 8;
  rtr.data[0] = 0xEE;  // an RTR carries no data: must not reach the wire

  const CanFrame* frames[] = {&std_frame, &ext, &rtr};
  can_frame expected[3];
  for (can_frame& e : expected) std::memset(&e, 0, sizeof e);
  expected[0].can_id = 0x080;
  expected[1].can_id = CAN_EFF_FLAG | 0x1ABCDEF0;
  expected[1].can_dlc = 5;
  for (int i = 0; i < 5; ++i) expected[1].data[i] = static_cast<std::uint8_t>(0x50 + i);
  expected[2].can_id = CAN_RTR_FLAG | 0x705;
  expected[2].can_dlc = 8;

  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    ASSERT_EQ(bus_->send(*frames[k]), HalStatus::kOk) << bus_->last_error();
    unsigned char raw[sizeof(can_frame) + 8];
    ASSERT_EQ(::recv(peer_, raw, sizeof raw, MSG_DONTWAIT), static_cast<ssize_t>(sizeof(can_frame)));
    EXPECT_EQ(std::memcmp(raw, &expected[k], sizeof(can_frame)), 0);
  }
}

TEST_F(SocketCanPair, SendRefusesFramesTheWireCannotCarry) {
  CanFrame f;
  f.dlc = 9;
  EXPECT_EQ(bus_->send(f), HalStatus::kMalformed);
  EXPECT_TRUE(has_substr(bus_->last_error(), "dlc")) << bus_->last_error();
  f.dlc = 1;
  f.id = 0x800;
  EXPECT_EQ(bus_->send(f), HalStatus::kMalformed);
  EXPECT_TRUE(has_substr(bus_->last_error(), "11 bits")) << bus_->last_error();
  f.id = CAN_ERR_BUSOFF;
  f.error = true;
  EXPECT_EQ(bus_->send(f), HalStatus::kMalformed);
  can_frame cf;
  EXPECT_EQ(take(&cf), -1) << "nothing may be written";
}

TEST_F(SocketCanPair, FullSendBufferGivesWouldBlock) {
  const int small = 1;  // the kernel rounds it up to its minimum
  ASSERT_EQ(setsockopt(bus_->fd(), SOL_SOCKET, SO_SNDBUF, &small, sizeof small), 0);
  CanFrame f;
  f.id = 0x10;
  f.dlc = 8;
  int sent = 0;
  HalStatus s = HalStatus::kOk;
  while (sent < 100000 && (s = bus_->send(f)) == HalStatus::kOk) ++sent;
  EXPECT_EQ(s, HalStatus::kWouldBlock) << bus_->last_error();
  EXPECT_GT(sent, 0);
  EXPECT_TRUE(has_substr(bus_->last_error(), "send on pair0")) << bus_->last_error();

  // Once the peer drains, sending works again.
  can_frame cf;
  while (take(&cf) > 0) {
  }
  EXPECT_EQ(bus_->send(f), HalStatus::kOk) << bus_->last_error();
}

TEST_F(SocketCanPair, PeerGoneIsClosedAfterQueuedFrames) {
  put(make_kernel_frame(0x1, 1));
  put(make_kernel_frame(0x2, 1));
  ::close(peer_);
  peer_ = -1;
  CanFrame f[4];
  HalStatus status{};
  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 2);
  EXPECT_EQ(status, HalStatus::kOk);
  EXPECT_EQ(bus_->receive(f, 4, 0, &status), 0);
  EXPECT_EQ(status, HalStatus::kClosed);
  EXPECT_EQ(bus_->receive(f, 4, 100 * kMs, &status), 0);
  EXPECT_EQ(status, HalStatus::kClosed);
  CanFrame out;
  EXPECT_EQ(bus_->send(out), HalStatus::kClosed);
  EXPECT_TRUE(has_substr(bus_->last_error(), "Broken pipe")) << bus_->last_error();
}

TEST_F(SocketCanPair, SteadyStateSendAndReceiveDoNotAllocate) {
  // A stamped receive path either way; the nanosecond one where it exists.
  ASSERT_NO_FATAL_FAILURE(make_bus(option_available(SO_TIMESTAMPNS) ? SO_TIMESTAMPNS : SO_TIMESTAMP));
  const can_frame in = make_kernel_frame(0x181, 8);
  const can_frame err = make_error_frame(CAN_ERR_BUSOFF);
  const unsigned char junk[3] = {};
  CanFrame out;
  out.id = 0x80;
  CanFrame got[4];
  HalStatus status{};
  can_frame echo;
  // Warm-up outside the scope: first use of anything lazily set up.
  put(in);
  ASSERT_EQ(bus_->receive(got, 4, 0, &status), 1);
  ASSERT_EQ(bus_->send(out), HalStatus::kOk);
  ASSERT_EQ(take(&echo), static_cast<ssize_t>(sizeof echo));

  int received = 0;
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 200; ++i) {
      ::send(peer_, &in, sizeof in, MSG_DONTWAIT);
      ::send(peer_, &err, sizeof err, MSG_DONTWAIT);
      ::send(peer_, junk, sizeof junk, MSG_DONTWAIT);
      received += bus_->receive(got, 4, 1 * kMs, &status);
      received += bus_->receive(got, 4, 0, &status);  // would block
      if (bus_->send(out) == HalStatus::kOk) ::recv(peer_, &echo, sizeof echo, MSG_DONTWAIT);
    }
    received += bus_->receive(got, 4, 1 * kMs, &status);  // timeout path
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(received, 400);
  EXPECT_EQ(bus_->malformed(), 200);
}

}  // namespace socketcan_bus_test
