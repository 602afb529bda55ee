// Filter instances and GNSS: the loop's tick with one instance and with
// robot_localization's dual EKF (a local instance in odom, a global one in
// map with a navsat sensor), and the navsat transform's cost per fix.
// Figures: docs/performance.md ("Filter instances and GNSS").
#include <benchmark/benchmark.h>

#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "estimation/geodesy.hpp"
#include "estimation/navsat_transform.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/pipeline/publisher.hpp"
#include "support/alloc_counter.hpp"

namespace {

using rtfuse::test::AllocScope;
namespace est = rtfuse::est;

// Wheels (vx vy vyaw) and an IMU (yaw, vyaw) in the first instance; with
// `instances` = 2 a global one fuses the same plus GNSS (x y), else the
// GNSS goes to the first instance (in odom, as a single-filter set-up).
std::string config_text(int instances) {
  std::string t = R"(
[filter]
frequency = 50
sensor_timeout = 0.5
two_d_mode = true
smooth_lagged_data = true
history_length = 0.5
[[sensor]]
name = "odom0"
type = "odometry"
channel = "odom"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
[[sensor]]
name = "imu0"
type = "imu"
channel = "imu"
config = [false, false, false, false, false, true, false, false, false, false, false, true, false, false, false]
)";
  const std::string gps = R"(
name = "gps0"
type = "navsat"
channel = "fix"
config = [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
datum = [47.3977, 8.5456, 0.0]
zero_altitude = true
)";
  if (instances == 1) return t + "[[sensor]]" + gps;
  return t + R"(
[[instance]]
name = "global"
world_frame = "map"
[[instance.sensor]]
name = "odom0"
type = "odometry"
channel = "odom"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
[[instance.sensor]]
name = "imu0"
type = "imu"
channel = "imu"
config = [false, false, false, false, false, true, false, false, false, false, false, true, false, false, false]
[[instance.sensor]])" + gps;
}

template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Every input type starts with the 8-byte fingerprint then header_t.utime.
void patch_utime(std::vector<std::uint8_t>& bytes, std::int64_t utime) {
  const auto u = static_cast<std::uint64_t>(utime);
  for (int i = 0; i < 8; ++i) bytes[8 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (56 - 8 * i));
}

// A robot at 1 m/s east: odometry, IMU and (every 10th tick, 5 Hz) a fix
// of where it is, so every fix is fused.
struct Inputs {
  Inputs() {
    rtfuse::odometry_t o{};
    o.header.frame_id = "odom";
    o.child_frame_id = "base_link";
    o.pose.pose.orientation.w = 1.0;
    for (int i = 0; i < 6; ++i) o.twist.covariance[i * 7] = 1e-3;
    o.twist.twist.linear.x = 1.0;
    odom = encode(o);
    rtfuse::imu_t m{};
    m.header.frame_id = "base_link";
    m.orientation = {0.0, 0.0, 0.0, 1.0};
    for (int i = 0; i < 3; ++i) m.orientation_covariance[i * 4] = 1e-3;
    for (int i = 0; i < 3; ++i) m.angular_velocity_covariance[i * 4] = 1e-4;
    m.linear_acceleration_covariance[0] = -1;
    imu = encode(m);
  }
  // The fix for base_link at `east` metres, a new message (the loop decodes
  // what the LCM thread would have).
  std::vector<std::uint8_t> fix(double east) const {
    est::LocalTangentPlane plane;
    plane.reset({47.3977, 8.5456, 0.0});
    const est::GeodeticPosition p = plane.reverse(Eigen::Vector3d(east, 0.0, 0.0));
    rtfuse::navsat_fix_t f{};
    f.header.frame_id = "base_link";
    f.status = rtfuse::navsat_fix_t::STATUS_FIX;
    f.latitude = p.latitude_deg;
    f.longitude = p.longitude_deg;
    f.altitude = p.altitude_m;
    f.position_covariance[0] = f.position_covariance[4] = 0.25;
    f.position_covariance[8] = 1.0;
    f.position_covariance_type = rtfuse::navsat_fix_t::COVARIANCE_TYPE_DIAGONAL_KNOWN;
    return encode(f);
  }
  std::vector<std::uint8_t> odom, imu;
};

class NullSink final : public rtfuse::MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, rtfuse::TimeNs) override { return true; }
};

// The loop's tick (FusionCore::tick and the publisher's schedule, as
// TickPipeline::step runs them) at 50 Hz, one and two instances; the
// messages are decoded outside the measurement, as on the LCM thread.
void BM_LoopTickInstances(benchmark::State& state) {
  const int instances = static_cast<int>(state.range(0));
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(config_text(instances), "<bench>");
  if (!loaded.config) {
    state.SkipWithError(("config: " + loaded.errors.front().to_string()).c_str());
    return;
  }
  std::string error;
  std::unique_ptr<rtfuse::FusionCore> core = rtfuse::FusionCore::create(*loaded.config, &error);
  if (!core) {
    state.SkipWithError(error.c_str());
    return;
  }
  rtfuse::Publisher publisher(core->config());
  Inputs in;
  // Two minutes of fixes, made up front: nothing in the loop allocates.
  std::vector<std::vector<std::uint8_t>> fixes;
  for (int i = 0; i < 600; ++i) fixes.push_back(in.fix(0.2 * i));
  rtfuse::LoopStats loop;
  std::int64_t tick = 0;
  auto cycle = [&]() {
    const std::int64_t t_us = 1'000'000 + tick * 20'000;
    const rtfuse::TimeNs t = rtfuse::utime_to_ns(t_us);
    patch_utime(in.imu, t_us);
    core->input().on_message("imu", in.imu.data(), static_cast<int>(in.imu.size()), t);
    patch_utime(in.odom, t_us);
    core->input().on_message("odom", in.odom.data(), static_cast<int>(in.odom.size()), t);
    if (tick % 10 == 0) {
      std::vector<std::uint8_t>& f = fixes[static_cast<std::size_t>((tick / 10) % 600)];
      patch_utime(f, t_us);
      core->input().on_message("fix", f.data(), static_cast<int>(f.size()), t);
    }
    ++loop.ticks;
    core->tick(t + 1'000'000, loop);
    benchmark::DoNotOptimize(publisher.schedule(core->last_snapshot(), t + 1'000'000));
    ++tick;
  };
  for (int i = 0; i < 100; ++i) cycle();
  AllocScope allocs;
  rtfuse::Snapshot s0;
  core->snapshot().load(s0);
  for (auto _ : state) cycle();
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
  rtfuse::Snapshot s1;
  core->snapshot().load(s1);
  state.counters["fused_per_iter"] = benchmark::Counter(
      static_cast<double>(s1.loop.measurements_fused - s0.loop.measurements_fused), benchmark::Counter::kAvgIterations);
  const int gps = core->config().num_sensors - 1;
  if (s1.sensors[gps].accepted < 10) state.SkipWithError("the fixes were not fused");
}
BENCHMARK(BM_LoopTickInstances)->ArgName("instances")->Arg(1)->Arg(2);

// One fix through navsat_transform (estimation/navsat_transform.hpp):
// checks, geodetic -> ECEF -> ENU, the lever arm, the covariance into the
// world frame. The EKF update it feeds is BM_EkfCorrect* territory.
void BM_NavsatConvert(benchmark::State& state) {
  est::NavsatParams p;
  p.manual_datum = true;
  p.datum = {47.3977, 8.5456, 0.0};
  p.zero_altitude = true;
  p.base_p_antenna = Eigen::Vector3d(0.3, 0.0, 0.8);
  est::NavsatTransform n(p);
  Inputs in;
  std::vector<est::NavSatFixSample> fixes;
  est::LocalTangentPlane plane;
  plane.reset(p.datum);
  for (int i = 0; i < 64; ++i) {
    est::NavSatFixSample f;
    f.status = 0;
    f.covariance_type = 2;
    f.position = plane.reverse(Eigen::Vector3d(0.1 * i, 0.05 * i, 0.0));
    f.covariance.diagonal() << 0.25, 0.25, 1.0;
    fixes.push_back(f);
  }
  rtfuse::geometry::RigidTransform world_T_base;
  est::PoseSample out;
  std::int64_t i = 0, refused = 0;
  AllocScope allocs;
  for (auto _ : state) {
    world_T_base.translation = Eigen::Vector3d(0.1 * static_cast<double>(i % 64), 0.0, 0.0);
    refused += n.convert(1'000'000'000 + i * 200'000'000, fixes[static_cast<std::size_t>(i % 64)], world_T_base,
                         &out) != est::NavsatRejection::kNone;
    benchmark::DoNotOptimize(out);
    ++i;
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocs.count()), benchmark::Counter::kAvgIterations);
  if (refused > static_cast<std::int64_t>(state.iterations()) / 10) {
    std::ostringstream why;
    why << refused << " of " << state.iterations() << " fixes refused";
    state.SkipWithError(why.str().c_str());
  }
}
BENCHMARK(BM_NavsatConvert);

}  // namespace
