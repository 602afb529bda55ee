// The last stage before the wheels: the path follower, the clearance check
// and the command gate, fed a sequence of steps read from the bytes (paths,
// poses, stamps, flags, speeds and commands, each number either a raw
// double, so NaN, infinities, subnormals and 1e308 all come, or a small
// fixed-point value, so that real driving does too).
//
// Format: byte 0 picks the parameters (the defaults; no curvature and no
// approach regulation; a fast, twitchy base), bytes 1..8 the bits of an
// 8 x 8 costmap (lethal or free, 0.5 m cells from (-2, -2)). Then records
// until the bytes run out, each starting with an op byte: op % 5 == 0 sets
// a path (a count byte, up to 39 points: more than the follower holds);
// anything else is a step: pose (x, y, yaw), a flags byte, the time's
// advance, the estimate's and the map's ages, then as the flags say a
// speed, a command replacing the follower's, a geometry for the check. A
// number is a tag byte, then 8 raw bytes (odd tag) or 2 (int16 / 1000).
//
// Properties: the follower's command is finite, linear in [0, max],
// |angular| at most max, its distances finite and not negative, its index
// on the path; the gate's reason is decide()'s; a stop is exactly zero;
// a drive is finite, within the limits and moved from the last command by
// at most the acceleration limits over a dt in (0, 2 periods].
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz_check.hpp"
#include "navigation/command_gate.hpp"
#include "navigation/path_clearance.hpp"
#include "navigation/path_follower.hpp"

namespace {

using namespace rtfuse::navigation;
using rtfuse::TimeNs;

constexpr int kCapacity = 32;
constexpr int kMaxPathBytes = 39;

struct Bytes {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;

  bool empty() const { return at >= size; }
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
  double number() {
    const std::uint8_t tag = byte();
    if (tag & 1) {
      std::uint8_t raw[8] = {};
      for (std::uint8_t& b : raw) b = byte();
      double d;
      std::memcpy(&d, raw, sizeof d);
      return d;
    }
    const auto lo = byte();
    const auto hi = byte();
    return static_cast<std::int16_t>(static_cast<std::uint16_t>(lo | hi << 8)) / 1000.0;
  }
  TimeNs stamp() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(byte()) << (8 * i);
    return static_cast<TimeNs>(v);
  }
};

FollowerParams preset(std::uint8_t which) {
  FollowerParams p;
  switch (which % 3) {
    case 1:
      p.regulated_min_radius_m = 0.0;
      p.approach_distance_m = 0.0;
      break;
    case 2:
      p.max_linear_mps = 2.0;
      p.max_angular_rps = 4.0;
      p.max_linear_accel_mps2 = 50.0;
      p.max_linear_decel_mps2 = 0.01;
      p.max_angular_accel_rps2 = 100.0;
      p.min_lookahead_m = 0.05;
      p.lookahead_time_s = 0.0;
      p.goal_tolerance_m = 0.01;
      p.command_rate_hz = 1000.0;
      break;
    default: break;
  }
  return p;
}

// now + delta, wrapping as the clock's caller might after a raw stamp
// near the end of the range (in the harness, not undefined behaviour).
TimeNs wrap_add(TimeNs now, std::int64_t delta) {
  return static_cast<TimeNs>(static_cast<std::uint64_t>(now) + static_cast<std::uint64_t>(delta));
}

bool within(const Velocity2& v, const FollowerParams& p) {
  return std::isfinite(v.linear) && std::isfinite(v.angular) && v.linear >= 0.0 && v.linear <= p.max_linear_mps &&
         std::fabs(v.angular) <= p.max_angular_rps;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  const FollowerParams p = preset(in.byte());
  PathFollower follower(p, kCapacity);
  CommandGate gate(p);
  std::uint8_t cost[64];
  for (int row = 0; row < 8; ++row) {
    const std::uint8_t bits = in.byte();
    for (int col = 0; col < 8; ++col) cost[row * 8 + col] = (bits >> col & 1) ? kCostLethal : kCostFree;
  }
  const CostView costs{cost, 8, 8};
  const double period = 1.0 / p.command_rate_hz;

  Point2 path[kMaxPathBytes];
  TimeNs now = 1'000'000'000;
  Velocity2 last;
  while (!in.empty()) {
    const std::uint8_t op = in.byte();
    if (op % 5 == 0) {
      const int n = in.byte() % (kMaxPathBytes + 1);
      for (int i = 0; i < n; ++i) path[i] = Point2{in.number(), in.number()};
      const bool taken = follower.set_path(path, n);
      FUZZ_CHECK(taken == follower.has_path(), "a refused path is not kept");
      FUZZ_CHECK(!taken || (n >= 1 && n <= kCapacity), "only paths that fit are taken");
      continue;
    }
    const Pose2 pose{in.number(), in.number(), in.number()};
    const std::uint8_t flags = in.byte();
    if (flags & 0x20) {
      now = in.stamp();
    } else {
      now = wrap_add(now, static_cast<TimeNs>(in.byte()) * 5'000'000);  // up to 1.275 s
    }
    GateInput g;
    g.now = now;
    g.enabled = (flags & 0x01) == 0;
    g.stop_requested = (flags & 0x02) != 0;
    g.have_goal = (flags & 0x04) == 0;
    g.estimate_stamp = wrap_add(now, -static_cast<TimeNs>(in.byte()) * 10'000'000);  // up to 2.55 s old
    g.map_stamp = (flags & 0x40) ? 0 : wrap_add(now, -static_cast<TimeNs>(in.byte()) * 50'000'000);  // 12.75 s
    const double speed = (flags & 0x08) ? in.number() : last.linear;

    const FollowResult r = follower.follow(pose, speed);
    FUZZ_CHECK(within(r.command, p), "the follower's command within the limits");
    FUZZ_CHECK(std::isfinite(r.remaining_m) && r.remaining_m >= 0.0, "a finite distance left");
    FUZZ_CHECK(std::isfinite(r.cross_track_m) && r.cross_track_m >= 0.0, "a finite cross-track distance");
    FUZZ_CHECK(std::isfinite(r.curvature) && std::isfinite(r.lookahead_m), "a finite curvature and lookahead");
    FUZZ_CHECK(!follower.has_path() || (r.nearest_index >= 0 && r.nearest_index < follower.path_size()),
               "the nearest index on the path");
    if (r.state == FollowState::kRotating) FUZZ_CHECK(r.command.linear == 0.0, "turning in place stands");

    Velocity2 desired = r.command;
    if (flags & 0x10) desired = Velocity2{in.number(), in.number()};
    GridGeometry geometry{-2.0, -2.0, 0.5};
    if (flags & 0x80) geometry = GridGeometry{in.number(), in.number(), in.number()};
    g.estimate_finite = usable(pose);
    g.have_path = follower.has_path();
    g.goal_reached = r.reached();
    g.path_blocked = follower.has_path() &&
                     path_blocked(costs, geometry, follower.path(), follower.path_size(), r.nearest_index, r.nearest,
                                  p.blocked_check_distance_m, static_cast<std::uint8_t>(p.lethal_from));

    const StopReason expected = gate.decide(g, desired);
    const GateOutput out = gate.step(g, desired);
    const Velocity2 c = out.command;
    FUZZ_CHECK(out.reason == expected, "the reason is decide()'s");
    FUZZ_CHECK(within(c, p), "the command within the limits");
    if (out.stopped()) {
      FUZZ_CHECK(c.linear == 0.0 && c.angular == 0.0, "a stop is an exact zero");
    } else {
      FUZZ_CHECK(out.dt_s > 0.0 && out.dt_s <= 2.0 * period + 1e-12, "dt within two periods");
      const double slack = 1e-9;
      FUZZ_CHECK(c.linear - last.linear <= p.max_linear_accel_mps2 * out.dt_s + slack, "linear acceleration");
      FUZZ_CHECK(last.linear - c.linear <= p.max_linear_decel_mps2 * out.dt_s + slack, "linear deceleration");
      FUZZ_CHECK(std::fabs(c.angular - last.angular) <= p.max_angular_accel_rps2 * out.dt_s + slack,
                 "angular acceleration");
    }
    last = c;
  }
  return 0;
}
