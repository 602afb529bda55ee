// rtfuse-canopen-node: the simulator's CiA 406 encoder nodes
// (sim/devices/canopen_encoder_node.hpp) on a real CAN interface. Each node
// boots, answers NMT, sends its heartbeat and a TPDO per SYNC, exactly as in
// the simulated robot, so the encoder driver (rtfused with backend "linux")
// can be bench-tested against SocketCAN without wheels: on a vcan interface,
// or on a real bus through a USB adapter with nothing else attached.
//
// Faults on a schedule (seconds since start): a node that goes silent and
// comes back, a counter that sticks, a counter that jumps. The kernel test
// (tests/kernel/can_i2c_test.cpp) plays the encoders this way.
//
// Exit: 0 after --duration or SIGINT/SIGTERM (a JSON summary on stdout),
// 1 interface failure, 2 usage.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "sim/devices/canopen_encoder_node.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }


// Frames the nodes send go straight onto the interface; a full TX queue
// (ENOBUFS on a busy bus) drops the frame as a real node's mailbox would.
class SocketCanWire final : public rtfuse::hal::mock::CanWire {
 public:
  explicit SocketCanWire(rtfuse::hal::CanBus& bus) : bus_(bus) {}
  bool transmit(const rtfuse::hal::CanFrame& frame, rtfuse::TimeNs) noexcept override {
    const rtfuse::hal::HalStatus s = bus_.send(frame);
    if (s == rtfuse::hal::HalStatus::kOk) {
      ++sent;
      return true;
    }
    ++failed;
    last_status = s;
    return false;
  }
  long long sent = 0;
  long long failed = 0;
  rtfuse::hal::HalStatus last_status = rtfuse::hal::HalStatus::kOk;

 private:
  rtfuse::hal::CanBus& bus_;
};

enum class FaultKind { kSilent, kStuck, kJump };

struct Fault {
  FaultKind kind;
  int node;
  double from_s;
  double to_s;        // kSilent, kStuck: end of the fault; kJump: unused
  long long counts;   // kJump
  bool started = false;
  bool ended = false;
};

// "ID:FROM:TO" (silent, stuck) or "ID:AT:COUNTS" (jump).
bool parse_fault(FaultKind kind, const std::string& spec, Fault* out, std::string* error) {
  const char* what = kind == FaultKind::kSilent ? "--silent" : kind == FaultKind::kStuck ? "--stuck" : "--jump";
  int node = 0;
  double a = 0;
  double b = 0;
  long long counts = 0;
  int used = 0;
  const bool ok = kind == FaultKind::kJump
                      ? std::sscanf(spec.c_str(), "%d:%lf:%lld%n", &node, &a, &counts, &used) == 3
                      : std::sscanf(spec.c_str(), "%d:%lf:%lf%n", &node, &a, &b, &used) == 3;
  if (!ok || used != static_cast<int>(spec.size())) {
    *error = std::string(what) + " " + spec + ": expected " +
             (kind == FaultKind::kJump ? "NODE:AT_S:COUNTS (e.g. 2:1.5:4000)" : "NODE:FROM_S:TO_S (e.g. 2:1.0:2.5)");
    return false;
  }
  if (a < 0 || (kind != FaultKind::kJump && b <= a)) {
    *error = std::string(what) + " " + spec + ": times must be >= 0 and the end after the start";
    return false;
  }
  *out = Fault{kind, node, a, b, counts};
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-canopen-node: simulated CiA 406 encoder nodes on a real CAN interface"};
  std::string ifname;
  std::vector<int> node_ids;
  double speed = 1000.0;
  double heartbeat_ms = 100.0;
  double duration_s = 0.0;
  int width = 4;
  std::vector<std::string> silent, stuck, jump;
  cli.option("-i,--interface", &ifname, "CAN interface (vcan0, can0)").required();
  cli.option("-n,--node", &node_ids, "node id 1..127 (repeat for several)").required();
  cli.option("--speed", &speed, "shaft speed of every node, counts/s")
      .show_default();
  cli.option("--heartbeat-ms", &heartbeat_ms, "heartbeat period, ms (0: none)").show_default();
  cli.option("--width", &width, "position bytes in the TPDO, 1..4").show_default();
  cli.option("--duration", &duration_s, "seconds to run (0: until SIGINT/SIGTERM)").show_default();
  cli.option("--silent", &silent, "NODE:FROM_S:TO_S: the node is off the bus in that window");
  cli.option("--stuck", &stuck, "NODE:FROM_S:TO_S: the node's counter stops in that window");
  cli.option("--jump", &jump, "NODE:AT_S:COUNTS: the node's counter jumps by COUNTS");
  if (const auto exit = cli.parse(argc, argv)) return *exit;

  std::vector<rtfuse::sim::CanopenEncoderNode> nodes;
  nodes.reserve(node_ids.size());
  for (int id : node_ids) {
    if (id < 1 || id > 127) {
      std::fprintf(stderr, "rtfuse-canopen-node: --node %d: CANopen node ids are 1..127\n", id);
      return 2;
    }
    rtfuse::sim::CanopenEncoderConfig c;
    c.node_id = static_cast<std::uint8_t>(id);
    c.heartbeat_period_ns = static_cast<rtfuse::TimeNs>(heartbeat_ms * 1e6);
    c.position_width = static_cast<std::uint8_t>(width);
    c.speed_counts_per_s = speed;
    nodes.emplace_back(c);
    if (!nodes.back().valid()) {
      std::fprintf(stderr, "rtfuse-canopen-node: --width %d: the position is 1..4 bytes\n", width);
      return 2;
    }
  }
  std::vector<Fault> faults;
  std::string error;
  for (auto [kind, specs] : {std::pair{FaultKind::kSilent, &silent}, std::pair{FaultKind::kStuck, &stuck},
                             std::pair{FaultKind::kJump, &jump}}) {
    for (const std::string& spec : *specs) {
      Fault f{};
      if (!parse_fault(kind, spec, &f, &error)) {
        std::fprintf(stderr, "rtfuse-canopen-node: %s\n", error.c_str());
        return 2;
      }
      bool known = false;
      for (int id : node_ids) known = known || id == f.node;
      if (!known) {
        std::fprintf(stderr, "rtfuse-canopen-node: %s: node %d is not one of the --node ids\n", spec.c_str(), f.node);
        return 2;
      }
      faults.push_back(f);
    }
  }

  // The nodes hear NMT and SYNC only: the kernel drops the rest (other
  // nodes' TPDOs, whatever else the bus carries) before the socket.
  const rtfuse::hal::CanIdFilter filters[] = {{rtfuse::sim::canopen::kNmtCobId, 0x7FF, false},
                                              {rtfuse::sim::canopen::kSyncCobId, 0x7FF, false}};
  auto bus = rtfuse::hal::SocketCanBus::open(ifname, filters, 2, &error);
  if (!bus) {
    std::fprintf(stderr, "rtfuse-canopen-node: %s\n", error.c_str());
    return 1;
  }
  SocketCanWire wire(*bus);

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  rtfuse::hal::MonotonicClock clock;
  const rtfuse::TimeNs t0 = clock.now();
  for (auto& n : nodes) n.set_speed(speed, t0);
  const rtfuse::TimeNs end = duration_s > 0 ? t0 + static_cast<rtfuse::TimeNs>(duration_s * 1e9) : 0;
  long long frames_heard = 0;
  long long syncs = 0;
  rtfuse::hal::CanFrame rx[32];
  while (g_stop == 0) {
    const rtfuse::TimeNs now = clock.now();
    if (end != 0 && now >= end) break;
    const double t = static_cast<double>(now - t0) / 1e9;
    for (Fault& f : faults) {
      for (auto& n : nodes) {
        if (n.node_id() != f.node) continue;
        if (!f.started && t >= f.from_s) {
          f.started = true;
          if (f.kind == FaultKind::kSilent) n.set_silent(true, now);
          if (f.kind == FaultKind::kStuck) n.set_stuck(true, now);
          if (f.kind == FaultKind::kJump) n.jump(f.counts);
        }
        if (f.started && !f.ended && f.kind != FaultKind::kJump && t >= f.to_s) {
          f.ended = true;
          if (f.kind == FaultKind::kSilent) n.set_silent(false, now);
          if (f.kind == FaultKind::kStuck) n.set_stuck(false, now);
        }
      }
    }
    for (auto& n : nodes) n.advance(now, wire);
    // A short wait keeps heartbeats within 2 ms of their due time.
    rtfuse::hal::HalStatus status = rtfuse::hal::HalStatus::kOk;
    const int got = bus->receive(rx, 32, 2'000'000, &status);
    if (got == 0 && status == rtfuse::hal::HalStatus::kClosed) {
      std::fprintf(stderr, "rtfuse-canopen-node: %s: %s\n", ifname.c_str(), bus->last_error());
      return 1;
    }
    for (int i = 0; i < got; ++i) {
      ++frames_heard;
      if (rx[i].id == rtfuse::sim::canopen::kSyncCobId && !rx[i].error) ++syncs;
      for (auto& n : nodes) n.on_frame(rx[i], clock.now(), wire);
    }
  }

  const rtfuse::TimeNs now = clock.now();
  // start_ns (CLOCK_MONOTONIC) lets a test on the same machine place the
  // fault windows on its own clock.
  std::printf("{\"interface\": \"%s\", \"start_ns\": %lld, \"seconds\": %.3f, \"frames_heard\": %lld, \"syncs\": %lld, \"sent\": %lld, "
              "\"send_failures\": %lld, \"nodes\": [",
              ifname.c_str(), static_cast<long long>(t0), static_cast<double>(now - t0) / 1e9, frames_heard, syncs, wire.sent, wire.failed);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto& n = nodes[i];
    std::printf("%s{\"id\": %d, \"state\": %d, \"boots\": %d, \"tpdos\": %lld, \"counts\": %lld}", i ? ", " : "",
                n.node_id(), static_cast<int>(n.nmt_state()), n.boot_count(), static_cast<long long>(n.tpdo_count()),
                static_cast<long long>(n.counts_at(now)));
  }
  std::printf("]}\n");
  return 0;
}
