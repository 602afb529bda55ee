// The SocketCAN backend (hal/linux/socketcan_bus) and the CANopen encoder
// master on the kernel's virtual CAN driver, vcan, with can-raw: run inside
// Debian's kernel under qemu by kernel_vm.sh. The encoders are another
// process, rtfuse-canopen-node (the simulator's node model on the wire).
//
// What vcan does that the tests lean on: it echoes every frame a socket
// sends to every other CAN_RAW socket on the interface (loopback), with the
// kernel's receive stamp; frames carrying CAN_ERR_FLAG are delivered only to
// sockets whose CAN_RAW_ERR_FILTER asks for their class, which is how a real
// controller's error frames reach the backend, so bus-off and error-passive
// can be played on it without a controller.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "drivers/canopen/canopen_encoders.hpp"
#include "hal/linux/socketcan_bus.hpp"

namespace {

using rtfuse::TimeNs;
using rtfuse::monotonic_now_ns;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::CanIdFilter;
using rtfuse::hal::HalStatus;
using rtfuse::hal::SocketCanBus;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSecond = 1'000'000'000;
constexpr const char* kIf = "vcan0";

void sleep_until(TimeNs t) {
  timespec ts{static_cast<time_t>(t / kSecond), static_cast<long>(t % kSecond)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

int run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// A second, plain CAN_RAW socket on the interface: the "other devices" on
// the bus, sending whatever a test needs, error frames included.
class RawCan {
 public:
  RawCan() {
    fd_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd_ < 0) return;
    sockaddr_can addr{};
    addr.can_family = AF_CAN;
    addr.can_ifindex = static_cast<int>(if_nametoindex(kIf));
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~RawCan() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  // errno on failure, 0 on success.
  int send(canid_t id, std::initializer_list<std::uint8_t> data) {
    can_frame f{};
    f.can_id = id;
    f.can_dlc = static_cast<__u8>(data.size());
    int i = 0;
    for (std::uint8_t b : data) f.data[i++] = b;
    return ::write(fd_, &f, sizeof f) == static_cast<ssize_t>(sizeof f) ? 0 : errno;
  }

 private:
  int fd_ = -1;
};

// Everything that arrives within `quiet` of the last frame.
std::vector<CanFrame> drain(SocketCanBus& bus, TimeNs quiet = 200 * kMs) {
  std::vector<CanFrame> out;
  CanFrame buf[16];
  for (;;) {
    HalStatus st = HalStatus::kOk;
    const int n = bus.receive(buf, 16, quiet, &st);
    if (n == 0) break;
    out.insert(out.end(), buf, buf + n);
  }
  return out;
}

class Vcan : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // The host's iproute2 in the guest's chroot; a second suite finds it made.
    if (if_nametoindex(kIf) == 0) {
      ASSERT_EQ(run(std::string("ip link add dev ") + kIf + " type vcan"), 0);
    }
    ASSERT_EQ(run(std::string("ip link set ") + kIf + " up"), 0);
  }
};

TEST_F(Vcan, FiltersPassOnlyTheirIdsAndFormat) {
  const CanIdFilter filters[] = {{0x181, 0x7FF, false}, {0x700, 0x780, false}};
  std::string error;
  auto bus = SocketCanBus::open(kIf, filters, 2, &error);
  ASSERT_NE(bus, nullptr) << error;
  RawCan other;
  ASSERT_TRUE(other.ok());
  ASSERT_EQ(other.send(0x181, {1}), 0);
  ASSERT_EQ(other.send(0x182, {2}), 0);                  // another id
  ASSERT_EQ(other.send(0x701, {3}), 0);                  // in the 0x700..0x77F range
  ASSERT_EQ(other.send(0x77F, {4}), 0);
  ASSERT_EQ(other.send(0x181 | CAN_EFF_FLAG, {5}), 0);   // same number, 29-bit: another frame format
  ASSERT_EQ(other.send(0x181 | CAN_RTR_FLAG, {}), 0);    // RTR passes like data
  ASSERT_EQ(other.send(0x281, {6}), 0);
  const std::vector<CanFrame> got = drain(*bus);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].id, 0x181u);
  EXPECT_EQ(got[0].data[0], 1);
  EXPECT_EQ(got[1].id, 0x701u);
  EXPECT_EQ(got[2].id, 0x77Fu);
  EXPECT_EQ(got[3].id, 0x181u);
  EXPECT_TRUE(got[3].rtr);
  for (const CanFrame& f : got) EXPECT_FALSE(f.extended);

  // No filters: everything, the 29-bit frame flagged as such.
  auto all = SocketCanBus::open(kIf, nullptr, 0, &error);
  ASSERT_NE(all, nullptr) << error;
  ASSERT_EQ(other.send(0x181 | CAN_EFF_FLAG, {5}), 0);
  ASSERT_EQ(other.send(0x282, {6}), 0);
  const std::vector<CanFrame> every = drain(*all);
  ASSERT_EQ(every.size(), 2u);
  EXPECT_TRUE(every[0].extended);
  EXPECT_EQ(every[0].id, 0x181u);
  EXPECT_EQ(every[1].id, 0x282u);
}

TEST_F(Vcan, KernelStampsAreMonotonicAndBracketTheSend) {
  std::string error;
  auto bus = SocketCanBus::open(kIf, nullptr, 0, &error);
  ASSERT_NE(bus, nullptr) << error;
  RawCan other;
  constexpr int kFrames = 8;
  TimeNs sent_at[kFrames];
  TimeNs t = monotonic_now_ns();
  for (int i = 0; i < kFrames; ++i) {
    t += 5 * kMs;
    sleep_until(t);
    sent_at[i] = monotonic_now_ns();
    ASSERT_EQ(other.send(0x100 + static_cast<canid_t>(i), {static_cast<std::uint8_t>(i)}), 0);
  }
  const TimeNs after = monotonic_now_ns();
  const std::vector<CanFrame> got = drain(*bus, 100 * kMs);
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    // The kernel stamps the frame when vcan hands it to the receivers:
    // after the write started, before we read it. The backend converts the
    // kernel's CLOCK_REALTIME stamp to CLOCK_MONOTONIC; 1 ms of slack for the
    // two clock reads of that conversion.
    EXPECT_GE(got[i].stamp, sent_at[i] - kMs) << i;
    EXPECT_LE(got[i].stamp, after + kMs) << i;
    if (i > 0) {
      EXPECT_GT(got[i].stamp, got[i - 1].stamp) << i;
    }
    // Each stamp belongs to its own send: before the next one started (vcan
    // hands the frame to the receivers within the sender's write()).
    if (i + 1 < kFrames) {
      EXPECT_LT(got[i].stamp, sent_at[i + 1] + kMs) << i;
    }
  }
  std::printf("stamp - send: first %.3f ms, last %.3f ms\n", (got[0].stamp - sent_at[0]) / 1e6,
              (got[kFrames - 1].stamp - sent_at[kFrames - 1]) / 1e6);
}

TEST_F(Vcan, ErrorFramesDriveTheBusState) {
  std::string error;
  auto bus = SocketCanBus::open(kIf, nullptr, 0, &error);
  ASSERT_NE(bus, nullptr) << error;
  EXPECT_EQ(bus->state(), CanBusState::kUnknown);
  RawCan controller;
  // What a controller driver sends through can_bus_off() and friends.
  ASSERT_EQ(controller.send(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_WARNING, 0, 0, 0, 0, 0, 0}), 0);
  std::vector<CanFrame> got = drain(*bus, 100 * kMs);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].error);
  EXPECT_EQ(bus->state(), CanBusState::kErrorWarning);
  ASSERT_EQ(controller.send(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 0, 0}), 0);
  (void)drain(*bus, 100 * kMs);
  EXPECT_EQ(bus->state(), CanBusState::kErrorPassive);
  ASSERT_EQ(controller.send(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0}), 0);
  (void)drain(*bus, 100 * kMs);
  EXPECT_EQ(bus->state(), CanBusState::kBusOff);
  // Bus errors "may flood" (linux/can/error.h): the backend does not ask for them.
  ASSERT_EQ(controller.send(CAN_ERR_FLAG | CAN_ERR_BUSERROR, {0, 0, 0, 0, 0, 0, 0, 0}), 0);
  EXPECT_TRUE(drain(*bus, 100 * kMs).empty());
  ASSERT_EQ(controller.send(CAN_ERR_FLAG | CAN_ERR_RESTARTED, {0, 0, 0, 0, 0, 0, 0, 0}), 0);
  (void)drain(*bus, 100 * kMs);
  EXPECT_EQ(bus->state(), CanBusState::kErrorActive);
}

TEST_F(Vcan, InterfaceDownIsClosedAndUpWorksAgain) {
  std::string error;
  auto bus = SocketCanBus::open(kIf, nullptr, 0, &error);
  ASSERT_NE(bus, nullptr) << error;
  CanFrame f;
  f.id = 0x123;
  f.dlc = 1;
  ASSERT_EQ(bus->send(f), HalStatus::kOk);
  ASSERT_EQ(run(std::string("ip link set ") + kIf + " down"), 0);
  EXPECT_EQ(bus->send(f), HalStatus::kClosed);
  EXPECT_NE(std::strstr(bus->last_error(), "Network is down"), nullptr) << bus->last_error();
  ASSERT_EQ(run(std::string("ip link set ") + kIf + " up"), 0);
  EXPECT_EQ(bus->send(f), HalStatus::kOk);
  // A socket bound to an interface that does not exist fails at open, naming it.
  EXPECT_EQ(SocketCanBus::open("vcan9", nullptr, 0, &error), nullptr);
  EXPECT_NE(error.find("vcan9"), std::string::npos) << error;
  std::printf("open vcan9: %s\n", error.c_str());
}

// --- the encoder master against rtfuse-canopen-node in another process -----------

class NodeProcess {
 public:
  explicit NodeProcess(std::vector<std::string> args) {
    out_ = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + "/canopen-node-" +
           std::to_string(::getpid()) + "-" + std::to_string(++count_) + ".json";
    pid_ = ::fork();
    if (pid_ == 0) {
      std::FILE* f = std::freopen(out_.c_str(), "w", stdout);
      (void)f;
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(RTFUSE_CANOPEN_NODE));
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(RTFUSE_CANOPEN_NODE, argv.data());
      std::_Exit(127);
    }
  }
  ~NodeProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      wait();
    }
  }
  // Exit code, and the JSON summary it printed.
  int wait() {
    int st = 0;
    if (pid_ > 0 && ::waitpid(pid_, &st, 0) == pid_) pid_ = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  std::string summary() const {
    std::string s;
    if (std::FILE* f = std::fopen(out_.c_str(), "r")) {
      char buf[4096];
      const std::size_t n = std::fread(buf, 1, sizeof buf, f);
      s.assign(buf, n);
      std::fclose(f);
    }
    return s;
  }

 private:
  pid_t pid_ = -1;
  std::string out_;
  static inline int count_ = 0;
};

rtfuse::drivers::CanopenEncodersConfig two_encoders() {
  rtfuse::drivers::CanopenEncodersConfig c;
  c.node_count = 2;
  c.nodes[0].node_id = 1;
  c.nodes[1].node_id = 2;
  c.heartbeat_timeout_ns = 300 * kMs;  // three 100 ms heartbeats
  c.tpdo_timeout_syncs = 10;
  c.max_counts_per_s = 20000;
  return c;
}

// One poll every 10 ms (100 Hz SYNC) until `until`; per poll, node 2's health.
struct Trace {
  std::vector<TimeNs> t;
  std::vector<rtfuse::drivers::EncoderHealth> health2;
  std::vector<std::int64_t> counts1;
  std::vector<TimeNs> stamp1;
  int sets = 0;
  int complete_sets = 0;
};

void poll_until(rtfuse::drivers::CanopenEncoders& enc, TimeNs until, Trace* tr,
                const std::function<void(TimeNs)>& each = nullptr) {
  TimeNs t = monotonic_now_ns();
  while (t < until) {
    enc.poll(t);
    rtfuse::drivers::EncoderSampleSet set;
    while (enc.take_sample_set(&set)) {
      ++tr->sets;
      if (set.valid_count == set.node_count) ++tr->complete_sets;
      if (set.readings[0].valid) {
        tr->counts1.push_back(set.readings[0].counts);
        tr->stamp1.push_back(set.readings[0].stamp);
      }
    }
    tr->t.push_back(t);
    tr->health2.push_back(enc.reading(1).health);
    if (each) each(t);
    t += 10 * kMs;
    sleep_until(t);
    t = monotonic_now_ns();
  }
}

TEST_F(Vcan, EncoderMasterPollsNodesInAnotherProcessThroughSilenceAndUnknownFrames) {
  std::string error;
  // Unfiltered, unlike rtfused's bus (LinuxHal filters to the nodes' COB-IDs
  // in the kernel): here the unknown frames must reach the driver.
  auto bus = SocketCanBus::open(kIf, nullptr, 0, &error);
  ASSERT_NE(bus, nullptr) << error;
  auto enc = rtfuse::drivers::CanopenEncoders::create(*bus, two_encoders(), &error);
  ASSERT_NE(enc, nullptr) << error;

  const TimeNs t0 = monotonic_now_ns();
  // Node 2 is off the bus from 2.0 s to 3.0 s of the node program's time.
  NodeProcess nodes({"-i", kIf, "-n", "1", "-n", "2", "--speed", "2000", "--heartbeat-ms", "100", "--duration",
                     "5", "--silent", "2:2.0:3.0"});
  ASSERT_TRUE(enc->start(t0));
  RawCan stranger;
  long long unknown_sent = 0;
  Trace tr;
  // From 3.5 s to 4.5 s a stranger floods the bus with ids nobody owns, one
  // per poll and a burst of 20 every 100 ms.
  poll_until(*enc, t0 + 4800 * kMs, &tr, [&](TimeNs t) {
    const TimeNs since = t - t0;
    if (since < 3500 * kMs || since > 4500 * kMs) return;
    const int burst = (since / (10 * kMs)) % 10 == 0 ? 20 : 1;
    for (int i = 0; i < burst; ++i) unknown_sent += stranger.send(0x555, {1, 2, 3}) == 0 ? 1 : 0;
  });
  ASSERT_EQ(nodes.wait(), 0);
  const std::string summary = nodes.summary();
  std::printf("node program: %s", summary.c_str());

  const auto& bs = enc->bus_stats();
  const auto& n1 = enc->node_stats(0);
  const auto& n2 = enc->node_stats(1);
  std::printf("master: %lld SYNCs, %d sets (%d complete), %lld frames, %lld unexpected, node1 %lld TPDOs, node2 %lld "
              "TPDOs %lld silent events %lld recoveries\n",
              (long long)bs.syncs_sent, tr.sets, tr.complete_sets, (long long)bs.frames_received,
              (long long)bs.unexpected_cob_ids, (long long)n1.tpdos, (long long)n2.tpdos,
              (long long)n2.silent_events, (long long)n2.recoveries);
  // Both nodes were started over NMT (their boot-up or pre-operational
  // heartbeat, whichever the master heard first) and answered SYNCs.
  EXPECT_GE(n1.nmt_starts + n2.nmt_starts, 2);
  EXPECT_GT(n1.tpdos, 200);
  EXPECT_GT(tr.complete_sets, 150);
  // Every frame of the stranger reached the driver and was counted, no more.
  EXPECT_GT(unknown_sent, 200);
  EXPECT_EQ(bs.unexpected_cob_ids, unknown_sent);
  EXPECT_EQ(bs.malformed_frames, 0);

  // Node 1's counts grow at the node's 2000 counts/s against the SYNC stamps
  // (the master's clock, the other process's shaft): within 2 %.
  ASSERT_GE(tr.counts1.size(), 100u);
  const double rate = static_cast<double>(tr.counts1.back() - tr.counts1.front()) /
                      (static_cast<double>(tr.stamp1.back() - tr.stamp1.front()) / 1e9);
  EXPECT_NEAR(rate, 2000.0, 40.0);
  std::printf("node 1 rate: %.1f counts/s over %zu samples\n", rate, tr.counts1.size());

  // Node 2: ok, then silent (detected after 10 SYNCs without a TPDO, before
  // the 300 ms heartbeat timeout), then ok again after it returns. The
  // silence is 2.0..3.0 s of the node program, placed on this clock by the
  // start time it reports. (Before 1 s the start-up may count a silence too:
  // the first SYNCs go out before the node program has booted.)
  const std::size_t at = summary.find("\"start_ns\": ");
  ASSERT_NE(at, std::string::npos);
  const TimeNs node_t0 = std::strtoll(summary.c_str() + at + 12, nullptr, 10);
  const TimeNs off = node_t0 + 2000 * kMs;
  const TimeNs on = node_t0 + 3000 * kMs;
  TimeNs silent_at = 0;
  TimeNs back_at = 0;
  int episodes = 0;
  bool was_silent = false;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (tr.t[i] < t0 + 1000 * kMs) continue;
    const bool silent = tr.health2[i] == rtfuse::drivers::EncoderHealth::kSilent;
    if (silent && !was_silent) {
      ++episodes;
      if (silent_at == 0) silent_at = tr.t[i];
    }
    if (silent_at != 0 && back_at == 0 && tr.health2[i] == rtfuse::drivers::EncoderHealth::kOk) back_at = tr.t[i];
    was_silent = silent;
  }
  std::printf("node 2 off the bus: detected %.0f ms after it went silent, valid again %.0f ms after it came back "
              "(node program started %.0f ms after the master)\n",
              (silent_at - off) / 1e6, (back_at - on) / 1e6, (node_t0 - t0) / 1e6);
  EXPECT_EQ(episodes, 1);
  EXPECT_GE(n2.recoveries, 1);
  // 10 SYNCs at 100 Hz, plus a poll period and scheduling slack under TCG.
  EXPECT_GE(silent_at - off, 90 * kMs);
  EXPECT_LE(silent_at - off, 250 * kMs);
  // Back with its first TPDO after a fresh heartbeat (the driver's rule): up
  // to a heartbeat period (100 ms) plus slack.
  EXPECT_GE(back_at - on, 0);
  EXPECT_LE(back_at - on, 250 * kMs);
  EXPECT_EQ(enc->reading(1).health, rtfuse::drivers::EncoderHealth::kOk);
}

TEST_F(Vcan, NodeThatRebootsIsStartedAgain) {
  std::string error;
  const CanIdFilter filters[] = {{0x181, 0x7FF, false}, {0x701, 0x7FF, false}, {0x081, 0x7FF, false}};
  auto bus = SocketCanBus::open(kIf, filters, 3, &error);
  ASSERT_NE(bus, nullptr) << error;
  auto cfg = two_encoders();
  cfg.node_count = 1;
  auto enc = rtfuse::drivers::CanopenEncoders::create(*bus, cfg, &error);
  ASSERT_NE(enc, nullptr) << error;
  const TimeNs t0 = monotonic_now_ns();
  ASSERT_TRUE(enc->start(t0));
  Trace tr;
  {
    NodeProcess first({"-i", kIf, "-n", "1", "--duration", "1.0"});
    poll_until(*enc, t0 + 1200 * kMs, &tr);
    ASSERT_EQ(first.wait(), 0);
  }
  const auto tpdos_first = enc->node_stats(0).tpdos;
  EXPECT_GT(tpdos_first, 40);
  // Power off for a while: the master gives up on it...
  poll_until(*enc, t0 + 1800 * kMs, &tr);
  EXPECT_EQ(enc->reading(0).health, rtfuse::drivers::EncoderHealth::kSilent);
  // ...and a freshly powered node (boot-up, pre-operational) gets an NMT start.
  NodeProcess second({"-i", kIf, "-n", "1", "--duration", "1.0"});
  poll_until(*enc, t0 + 3000 * kMs, &tr);
  ASSERT_EQ(second.wait(), 0);
  const auto& st = enc->node_stats(0);
  std::printf("node 1: %lld boot-ups, %lld NMT starts, %lld TPDOs (%lld before the reboot)\n",
              (long long)st.boot_ups, (long long)st.nmt_starts, (long long)st.tpdos, (long long)tpdos_first);
  EXPECT_GE(st.boot_ups, 1);
  EXPECT_GE(st.nmt_starts, 2);
  EXPECT_GT(st.tpdos, tpdos_first + 40);
  EXPECT_NE(second.summary().find("\"boots\": 1"), std::string::npos) << second.summary();
}

}  // namespace
