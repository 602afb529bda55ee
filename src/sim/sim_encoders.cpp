#include "sim/sim_encoders.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rtfuse::sim {

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
namespace canopen = sim::canopen;
}  // namespace

std::int64_t wheel_counts(const RobotBody& robot, const TruthState& truth, int wheel) noexcept {
  if (wheel < 0 || wheel >= truth.wheel_count || wheel >= kMaxSimWheels) return 0;
  const SimWheel& w = robot.wheels[static_cast<std::size_t>(wheel)];
  const double angle = truth.wheel_distance[wheel] / (robot.wheel_radius_m * (1.0 + w.radius_error));
  const bool inverted = w.left ? robot.invert_left : robot.invert_right;
  const double counts = (inverted ? -angle : angle) * robot.counts_per_rev * robot.gear_ratio / kTwoPi;
  return std::isfinite(counts) ? static_cast<std::int64_t>(std::floor(counts)) : 0;
}

std::int64_t wrap_position(std::int64_t counts, int bits, bool is_signed) noexcept {
  bits = std::clamp(bits, 1, 62);
  const std::uint64_t range = std::uint64_t{1} << bits;
  const std::uint64_t raw = static_cast<std::uint64_t>(counts) & (range - 1);
  if (is_signed && (raw >> (bits - 1)) != 0) return static_cast<std::int64_t>(raw) - static_cast<std::int64_t>(range);
  return static_cast<std::int64_t>(raw);
}

SimEncoders::SimEncoders(const DriveScenario& scenario, TruthSource& truth, const hal::Clock& clock, TimeNs t0)
    : truth_(truth),
      clock_(clock),
      t0_(t0),
      robot_(scenario.robot),
      wheel_count_(std::clamp(scenario.robot.wheel_count, 0, kMaxSimWheels)),
      bus_(hal::mock::MockCanBusCapacity{}, &clock) {
  for (int w = 0; w < wheel_count_; ++w) {
    sim::CanopenEncoderConfig c;
    c.node_id = robot_.wheels[static_cast<std::size_t>(w)].node_id;
    c.heartbeat_period_ns = robot_.heartbeat_period_ns;
    c.position_width = static_cast<std::uint8_t>((robot_.encoder_bits + 7) / 8);
    c.position_signed = robot_.encoder_signed;
    nodes_[w] = std::make_unique<sim::CanopenEncoderNode>(c);
  }
  for (int i = 0; i < scenario.dropout_count && i < kMaxDropouts; ++i) {
    const EncoderDropout& d = scenario.dropouts[static_cast<std::size_t>(i)];
    for (int w = 0; w < wheel_count_; ++w) {
      if (robot_.wheels[static_cast<std::size_t>(w)].node_id != d.node_id) continue;
      const TimeNs begin = t0 + sec_to_ns(d.start_s);
      edges_[edge_count_++] = DropoutEdge{begin, w, true};
      edges_[edge_count_++] = DropoutEdge{begin + sec_to_ns(d.duration_s), w, false};
    }
  }
  // In time order; at the same instant a window ends before the next begins.
  std::sort(edges_, edges_ + edge_count_, [](const DropoutEdge& a, const DropoutEdge& b) {
    return a.time != b.time ? a.time < b.time : (!a.begins && b.begins);
  });
  // Powered up with the robot: the boot-ups are the first frames on the bus.
  for (int w = 0; w < wheel_count_; ++w) bus_.attach(*nodes_[w]);
  update(clock.now());
}

SimEncoders::~SimEncoders() {
  for (int w = 0; w < wheel_count_; ++w) bus_.detach(*nodes_[w]);
}

void SimEncoders::update(TimeNs now) noexcept {
  while (next_edge_ < edge_count_ && edges_[next_edge_].time <= now) {
    const DropoutEdge& e = edges_[next_edge_++];
    // What the nodes had due before this instant goes out first, stamped when
    // it was due, so the frames stay in time order.
    for (int w = 0; w < wheel_count_; ++w) nodes_[w]->advance(e.time, bus_);
    sim::CanopenEncoderNode& node = *nodes_[e.wheel];
    if (e.begins) {
      node.set_silent(true, e.time);
      continue;
    }
    node.set_silent(false, e.time);
    // Power comes back: the node boots as after a reset (boot-up frame,
    // Pre-operational); the position is the absolute encoder's and survives.
    hal::CanFrame reset;
    reset.id = canopen::kNmtCobId;
    reset.dlc = 2;
    reset.data[0] = canopen::kNmtResetNode;
    reset.data[1] = node.node_id();
    if (node.booted()) {
      node.on_frame(reset, e.time, bus_);
    } else {
      node.advance(e.time, bus_);  // silent since power-up: this is its first boot
    }
    ++reboots_[e.wheel];
  }
  const TruthState s = truth_.truth_at(ns_to_sec(now - t0_));
  for (int w = 0; w < wheel_count_; ++w) {
    const std::int64_t counts = stuck_[w] ? stuck_value_[w] : wheel_counts(robot_, s, w) + offset_[w];
    nodes_[w]->set_position(wrap_position(counts, robot_.encoder_bits, robot_.encoder_signed), now);
  }
}

void SimEncoders::set_silent(int wheel, bool silent, TimeNs now) noexcept {
  if (wheel < 0 || wheel >= wheel_count_) return;
  update(now);
  nodes_[wheel]->set_silent(silent, now);
}

void SimEncoders::set_stuck(int wheel, bool stuck, TimeNs now) noexcept {
  if (wheel < 0 || wheel >= wheel_count_ || stuck == stuck_[wheel]) return;
  const std::int64_t truth_counts = wheel_counts(robot_, truth_.truth_at(ns_to_sec(now - t0_)), wheel);
  if (stuck) {
    stuck_value_[wheel] = truth_counts + offset_[wheel];
  } else {
    offset_[wheel] = stuck_value_[wheel] - truth_counts;  // counts on from the held value
  }
  stuck_[wheel] = stuck;
  update(now);
}

void SimEncoders::jump(int wheel, std::int64_t counts) noexcept {
  if (wheel < 0 || wheel >= wheel_count_) return;
  offset_[wheel] += counts;
  if (stuck_[wheel]) stuck_value_[wheel] += counts;
}

hal::HalStatus SimEncoders::send(const hal::CanFrame& frame) noexcept {
  update(clock_.now());
  return bus_.send(frame);
}

int SimEncoders::receive(hal::CanFrame* out, int max, TimeNs timeout_ns, hal::HalStatus* status) noexcept {
  update(clock_.now());
  return bus_.receive(out, max, timeout_ns, status);
}

void SimEncoders::provide(DeviceBuses& out, hal::Clock&) noexcept { out.can = this; }

TimeNs SimEncoders::next_event_time() noexcept { return std::numeric_limits<TimeNs>::max(); }

std::unique_ptr<SimDevice> make_sim_encoders(const SimDeviceContext& ctx, std::string* error) {
  const RobotBody& body = ctx.scenario.robot;
  const CanSection& can = ctx.cfg.hardware.can;
  const std::string& path = ctx.scenario_path;
  // The config must address the simulated encoders, or the driver would talk
  // to nobody and the run would say nothing useful.
  for (int i = 0; i < can.num_nodes; ++i) {
    const CanNodeSection& n = can.nodes[static_cast<std::size_t>(i)];
    const std::string node = ctx.cfg.source + ": can.node[" + std::to_string(i) + "]";
    bool found = false;
    for (int w = 0; w < body.wheel_count; ++w) {
      const SimWheel& wheel = body.wheels[static_cast<std::size_t>(w)];
      if (wheel.node_id != n.node_id) continue;
      found = true;
      // A counter of another width or signedness unwraps at the wrong
      // place: jumps and wrong counts, with no error to say why.
      if (n.position_bits != body.encoder_bits || n.position_signed != body.encoder_signed) {
        *error = node + " reads a " + std::to_string(n.position_bits) + "-bit " +
                 (n.position_signed ? "signed" : "unsigned") + " position but the simulated encoder in " + path +
                 " counts " + std::to_string(body.encoder_bits) + "-bit " +
                 (body.encoder_signed ? "signed" : "unsigned");
        return nullptr;
      }
      const bool inverted = wheel.left ? body.invert_left : body.invert_right;
      if ((n.sign < 0) != inverted) {
        *error = node + ".sign = " + std::to_string(n.sign) + " but the simulated encoder in " + path +
                 (inverted ? " counts down" : " counts up") + " driving forward";
        return nullptr;
      }
    }
    if (!found) {
      *error = node + ".node_id = " + std::to_string(n.node_id) + " is not an encoder of the simulated robot in " +
               path;
      return nullptr;
    }
  }
  return std::make_unique<SimEncoders>(ctx.scenario, ctx.truth, ctx.clock, ctx.t0);
}

}  // namespace rtfuse::sim
