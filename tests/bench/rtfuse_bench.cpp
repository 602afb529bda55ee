// rtfuse_bench: the figures docs/performance.md reports (run tools/bench.sh).
//
//   BM_EkfPredict            Ekf::predict(0.01) on a moving state
//   BM_EkfCorrectImu9        Ekf::correct, 9 variables (IMU: rpy, rates, accel)
//   BM_EkfCorrectTwist4      Ekf::correct, 4 variables (wheel odometry twist)
//   BM_EkfRestoreCopy        the state + covariance copy the correct benchmarks
//                            pay per iteration (subtract it to get correct alone)
//   BM_EkfPredictCorrectImu9 predict + 9-variable correct, the issue's < 0.8 µs pair
//   BM_LoopTick              decode one odometry_t and one imu_t + FusionCore::tick
//   BM_ReplayBag2            the shared 61.2 s Jackal bag replayed end to end
//
// Every per-cycle benchmark also reports allocs_per_iter: global operator new
// is replaced (tests/support/alloc_counter_impl.hpp) and counted while the
// timed loop runs. The real-time path must show 0.
//
// Nothing here asserts a timing; a benchmark that cannot do its job (data
// missing, measurement rejected) ends with SkipWithError and says why.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "estimation/ekf.hpp"
#include "geometry/rotation.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/replay/replay.hpp"
#include "support/alloc_counter.hpp"
#include "support/alloc_counter_impl.hpp"
#include "transport/event_log.hpp"

namespace {

using rtfuse::test::AllocScope;
namespace est = rtfuse::est;

// ---------------------------------------------------------------------------
// A realistic filter: a robot driving a gentle curve, dense covariances.

// A dense symmetric positive definite matrix with the given variances: a random
// correlation matrix (diagonally dominant Gram matrix, correlations up to
// ~0.3) scaled by the standard deviations. Deterministic (fixed seed).
est::StateMatrix dense_spd(const est::StateVector& variances, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  est::StateMatrix a;
  for (int i = 0; i < est::kStateSize; ++i) {
    for (int j = 0; j < est::kStateSize; ++j) a(i, j) = n(rng);
  }
  est::StateMatrix c = a * a.transpose() / est::kStateSize + est::StateMatrix::Identity() * 2.0;
  const est::StateVector d = c.diagonal().cwiseSqrt().cwiseInverse();
  c = d.asDiagonal() * c * d.asDiagonal();  // correlation matrix
  const est::StateVector s = variances.cwiseSqrt();
  est::StateMatrix p = s.asDiagonal() * c * s.asDiagonal();
  return 0.5 * (p + p.transpose());
}

est::StateVector moving_state() {
  est::StateVector x;
  //   x     y     z     roll   pitch  yaw   vx   vy    vz    vroll vpitch vyaw  ax   ay    az
  x << 1.2, -0.7, 0.1, 0.02, -0.01, 0.8, 0.8, 0.05, 0.01, 0.01, -0.02, 0.3, 0.2, 0.05, -0.02;
  return x;
}

est::StateMatrix moving_covariance() {
  est::StateVector v;
  //   position         orientation         linear velocity     angular velocity     acceleration
  v << 0.05, 0.05, 0.08, 0.004, 0.004, 0.01, 0.02, 0.02, 0.03, 0.002, 0.002, 0.004, 0.05, 0.05, 0.05;
  return dense_spd(v, 7);
}

// robot_localization's Jackal process noise (test_ekf_localization_node_bag2)
// made dense with the same correlation structure as the covariance.
est::StateMatrix dense_process_noise() {
  est::StateVector v;
  v << 0.03, 0.03, 0.04, 0.03, 0.03, 0.06, 0.025, 0.025, 0.05, 0.002, 0.002, 0.004, 0.01, 0.01, 0.01;
  return dense_spd(v, 11);
}

est::Ekf moving_ekf() {
  est::Ekf ekf;
  ekf.set_process_noise(dense_process_noise());
  ekf.set_state(moving_state());
  ekf.set_covariance(moving_covariance());
  return ekf;
}

// A 3x3 block with the given variances and mild correlation (0.1).
Eigen::Matrix3d block3(double v0, double v1, double v2) {
  const Eigen::Vector3d s(std::sqrt(v0), std::sqrt(v1), std::sqrt(v2));
  Eigen::Matrix3d c = Eigen::Matrix3d::Constant(0.1);
  c.diagonal().setOnes();
  return s.asDiagonal() * c * s.asDiagonal();
}

// What the IMU model hands the filter, as one 9-variable measurement: roll
// pitch yaw, vroll vpitch vyaw, ax ay az, each within ~1 sigma of the state.
est::Measurement imu9_measurement(const est::StateVector& x) {
  est::Measurement m;
  m.part = est::MeasurementPart::kPose;
  m.mask = est::kOrientationMask | est::kAngularVelocityMask | est::kAccelerationMask;
  m.z = x;
  m.z(est::kRoll) += 0.01;
  m.z(est::kPitch) -= 0.008;
  m.z(est::kYaw) += 0.02;
  m.z(est::kVroll) -= 0.004;
  m.z(est::kVpitch) += 0.003;
  m.z(est::kVyaw) += 0.01;
  m.z(est::kAx) += 0.05;
  m.z(est::kAy) -= 0.04;
  m.z(est::kAz) += 0.06;
  m.covariance.block<3, 3>(est::kRoll, est::kRoll) = block3(1e-3, 1e-3, 2e-3);
  m.covariance.block<3, 3>(est::kVroll, est::kVroll) = block3(4e-4, 4e-4, 4e-4);
  m.covariance.block<3, 3>(est::kAx, est::kAx) = block3(1e-2, 1e-2, 1e-2);
  m.mahalanobis_threshold = 10.0;  // finite, so the gate is exercised
  return m;
}

// Wheel odometry twist: vx vy vz vyaw.
est::Measurement twist4_measurement(const est::StateVector& x) {
  est::Measurement m;
  m.part = est::MeasurementPart::kTwist;
  m.mask = est::kLinearVelocityMask | est::mask_bit(est::kVyaw);
  m.z = x;
  m.z(est::kVx) += 0.03;
  m.z(est::kVy) -= 0.01;
  m.z(est::kVz) += 0.005;
  m.z(est::kVyaw) -= 0.02;
  const int idx[4] = {est::kVx, est::kVy, est::kVz, est::kVyaw};
  const double var[4] = {1e-3, 1e-3, 1e-3, 3e-2};
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      const double rho = a == b ? 1.0 : 0.05;
      m.covariance(idx[a], idx[b]) = rho * std::sqrt(var[a] * var[b]);
    }
  }
  m.mahalanobis_threshold = 10.0;
  return m;
}

void report_allocations(benchmark::State& state, std::size_t allocations) {
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
}

// ---------------------------------------------------------------------------
// EKF

// Predict-only from a realistic start. Every 100 predictions (1 s of dead
// reckoning at dt = 0.01) state and covariance are restored, so P never grows
// to the variance cap; the copy is amortised over the 100 (see BM_EkfRestoreCopy).
void BM_EkfPredict(benchmark::State& state) {
  est::Ekf ekf = moving_ekf();
  const est::StateVector x0 = ekf.state();
  const est::StateMatrix p0 = ekf.covariance();
  int k = 0;
  AllocScope allocs;
  for (auto _ : state) {
    ekf.predict(0.01);
    benchmark::DoNotOptimize(ekf);
    if (++k == 100) {
      k = 0;
      ekf.set_state(x0);
      ekf.set_covariance(p0);
    }
    benchmark::ClobberMemory();
  }
  report_allocations(state, allocs.count());
  if (!ekf.covariance().allFinite()) state.SkipWithError("predict produced a non-finite covariance");
}
BENCHMARK(BM_EkfPredict);

// The copy the correct benchmarks do per iteration to start from the same
// (realistic) state and covariance: state (120 B) + covariance (1800 B).
void BM_EkfRestoreCopy(benchmark::State& state) {
  est::Ekf ekf = moving_ekf();
  const est::StateVector x0 = ekf.state();
  const est::StateMatrix p0 = ekf.covariance();
  AllocScope allocs;
  for (auto _ : state) {
    ekf.set_state(x0);
    ekf.set_covariance(p0);
    benchmark::DoNotOptimize(ekf);
    benchmark::ClobberMemory();
  }
  report_allocations(state, allocs.count());
}
BENCHMARK(BM_EkfRestoreCopy);

// A correct alone, restored to the same prior every iteration (so P never
// collapses); the figure includes one BM_EkfRestoreCopy.
void correct_from_fixed_prior(benchmark::State& state, const est::Measurement& m, int expected_vars) {
  est::Ekf ekf = moving_ekf();
  const est::StateVector x0 = ekf.state();
  const est::StateMatrix p0 = ekf.covariance();
  std::int64_t fused = 0;
  AllocScope allocs;
  for (auto _ : state) {
    ekf.set_state(x0);
    ekf.set_covariance(p0);
    est::CorrectResult r = ekf.correct(m);
    fused += r.fused_variables == expected_vars;
    benchmark::DoNotOptimize(r);
    benchmark::DoNotOptimize(ekf);
    benchmark::ClobberMemory();
  }
  report_allocations(state, allocs.count());
  if (fused != static_cast<std::int64_t>(state.iterations())) {
    state.SkipWithError("the measurement was not fused every iteration (rejected?)");
  }
}

void BM_EkfCorrectImu9(benchmark::State& state) {
  correct_from_fixed_prior(state, imu9_measurement(moving_state()), 9);
}
BENCHMARK(BM_EkfCorrectImu9);

void BM_EkfCorrectTwist4(benchmark::State& state) {
  correct_from_fixed_prior(state, twist4_measurement(moving_state()), 4);
}
BENCHMARK(BM_EkfCorrectTwist4);

// One filter cycle as the loop runs it at 100 Hz: predict by 10 ms, then fuse
// the 9-variable IMU measurement. No restore: prediction and correction reach
// the filter's steady state (P stays realistic by construction), and every
// correction must be accepted by the Mahalanobis gate.
void BM_EkfPredictCorrectImu9(benchmark::State& state) {
  est::Ekf ekf = moving_ekf();
  const est::Measurement m = imu9_measurement(moving_state());
  std::int64_t fused = 0;
  AllocScope allocs;
  for (auto _ : state) {
    ekf.predict(0.01);
    est::CorrectResult r = ekf.correct(m);
    fused += r.fused_variables == 9;
    benchmark::DoNotOptimize(r);
    benchmark::DoNotOptimize(ekf);
    benchmark::ClobberMemory();
  }
  report_allocations(state, allocs.count());
  if (fused != static_cast<std::int64_t>(state.iterations())) {
    state.SkipWithError("the IMU measurement was not fused every iteration (rejected?)");
  } else if (!ekf.state().allFinite() || !ekf.covariance().allFinite()) {
    state.SkipWithError("the filter diverged");
  }
}
BENCHMARK(BM_EkfPredictCorrectImu9);

// ---------------------------------------------------------------------------
// Loop tick: decode + preprocessing + fusion + snapshot

// Two sensors as robot_localization's Jackal test: wheel odometry (vx vy vz
// vyaw) and an IMU (rpy, rates, accel, gravity removed).
rtfuse::RuntimeConfig jackal_config() {
  rtfuse::RuntimeConfig cfg;
  cfg.source = "<rtfuse_bench>";
  cfg.rate_hz = 50.0;
  cfg.world_frame = "odom";
  cfg.odom_frame = "odom";
  cfg.base_link_frame = "base_link";
  cfg.map_frame = "map";
  cfg.filter.sensor_timeout_s = 0.1;
  est::StateVector q;
  q << 0.03, 0.03, 0.04, 0.03, 0.03, 0.06, 0.025, 0.025, 0.05, 0.002, 0.002, 0.004, 0.01, 0.01, 0.01;
  cfg.filter.process_noise = q.asDiagonal();
  cfg.filter.initial_covariance = est::StateMatrix::Identity() * 1e-9;

  rtfuse::SensorConfig& odom = cfg.sensors[0];
  odom.name = "odom0";
  odom.channel = "odom";
  odom.params.kind = est::SensorKind::kOdometry;
  odom.params.update_mask = est::kLinearVelocityMask | est::mask_bit(est::kVyaw);
  odom.params.queue_size = 10;

  rtfuse::SensorConfig& imu = cfg.sensors[1];
  imu.name = "imu0";
  imu.channel = "imu";
  imu.params.kind = est::SensorKind::kImu;
  imu.params.update_mask = est::kOrientationMask | est::kAngularVelocityMask | est::kAccelerationMask;
  imu.params.remove_gravitational_acceleration = true;
  imu.params.queue_size = 10;
  cfg.num_sensors = 2;
  return cfg;
}

void set_diag(double* cov, int n, const double* variances) {
  for (int i = 0; i < n * n; ++i) cov[i] = 0.0;
  for (int i = 0; i < n; ++i) cov[i * n + i] = variances[i];
}

// A robot driving straight at 0.5 m/s, slightly tilted: odometry and IMU agree
// with each other, so the filter settles on a steady, moving solution.
constexpr double kRoll = 0.01, kPitch = -0.02, kYaw = 0.7, kSpeed = 0.5;

std::vector<std::uint8_t> encoded_odometry() {
  rtfuse::odometry_t msg{};
  msg.header.utime = 1'000'000;
  msg.header.frame_id = "odom";
  msg.child_frame_id = "base_link";
  msg.pose.pose.orientation.w = 1.0;
  const double pose_var[6] = {1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3};
  set_diag(msg.pose.covariance, 6, pose_var);
  msg.twist.twist.linear.x = kSpeed;
  const double twist_var[6] = {1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 3e-2};
  set_diag(msg.twist.covariance, 6, twist_var);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

std::vector<std::uint8_t> encoded_imu() {
  rtfuse::imu_t msg{};
  msg.header.utime = 1'000'000;
  msg.header.frame_id = "base_link";
  const Eigen::Quaterniond q = rtfuse::geometry::quaternion_from_rpy(kRoll, kPitch, kYaw);
  msg.orientation.x = q.x();
  msg.orientation.y = q.y();
  msg.orientation.z = q.z();
  msg.orientation.w = q.w();
  const double o_var[3] = {1e-3, 1e-3, 2e-3};
  set_diag(msg.orientation_covariance, 3, o_var);
  const double w_var[3] = {4e-4, 4e-4, 4e-4};
  set_diag(msg.angular_velocity_covariance, 3, w_var);
  // At constant velocity the accelerometer reads gravity only.
  const Eigen::Vector3d g = q.conjugate() * Eigen::Vector3d(0.0, 0.0, 9.80665);
  msg.linear_acceleration.x = g.x();
  msg.linear_acceleration.y = g.y();
  msg.linear_acceleration.z = g.z();
  const double a_var[3] = {1e-2, 1e-2, 1e-2};
  set_diag(msg.linear_acceleration_covariance, 3, a_var);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Every input type starts with the 8-byte fingerprint then header_t, whose
// first field is utime (int64, big-endian): the stamp is patched in place, as
// if the sensor had sent a new message.
constexpr std::size_t kUtimeOffset = 8;
inline void patch_utime(std::uint8_t* bytes, std::int64_t utime) {
  const auto u = static_cast<std::uint64_t>(utime);
  for (int i = 0; i < 8; ++i) bytes[kUtimeOffset + i] = static_cast<std::uint8_t>(u >> (56 - 8 * i));
}

// The benchmarks' FusionCore, or null with the benchmark skipped and why.
std::unique_ptr<rtfuse::FusionCore> create_core(benchmark::State& state, const rtfuse::RuntimeConfig& cfg) {
  std::string error;
  std::unique_ptr<rtfuse::FusionCore> core = rtfuse::FusionCore::create(cfg, &error);
  if (!core) state.SkipWithError(("FusionCore::create: " + error).c_str());
  return core;
}

void BM_LoopTick(benchmark::State& state) {
  const rtfuse::RuntimeConfig cfg = jackal_config();
  std::unique_ptr<rtfuse::FusionCore> core = create_core(state, cfg);
  if (!core) return;
  std::vector<std::uint8_t> odom = encoded_odometry();
  std::vector<std::uint8_t> imu = encoded_imu();
  {
    // The patched stamp must be what the decoder reads.
    patch_utime(odom.data(), 123456789);
    rtfuse::odometry_t check{};
    if (check.decode(odom.data(), 0, static_cast<int>(odom.size())) < 0 || check.header.utime != 123456789) {
      state.SkipWithError("header.utime is not where the benchmark patches it");
      return;
    }
  }
  const int odom_size = static_cast<int>(odom.size());
  const int imu_size = static_cast<int>(imu.size());

  // 50 Hz: IMU at t, odometry 10 ms later, the tick right after both.
  constexpr std::int64_t kPeriodUs = 20'000;
  std::int64_t t_us = 1'000'000;
  rtfuse::LoopStats loop;
  loop.rate_hz = 50.0;
  loop.period_ns = 20'000'000;
  auto cycle = [&]() {
    patch_utime(imu.data(), t_us);
    core->input().on_message("imu", imu.data(), imu_size, rtfuse::utime_to_ns(t_us));
    patch_utime(odom.data(), t_us + kPeriodUs / 2);
    core->input().on_message("odom", odom.data(), odom_size, rtfuse::utime_to_ns(t_us + kPeriodUs / 2));
    ++loop.ticks;
    core->tick(rtfuse::utime_to_ns(t_us + kPeriodUs / 2) + 1'000'000, loop);
    t_us += kPeriodUs;
  };
  // Warm up outside the measurement: initialisation, first-message paths.
  for (int i = 0; i < 100; ++i) cycle();

  rtfuse::Snapshot s0;
  core->snapshot().load(s0);
  AllocScope allocs;
  for (auto _ : state) {
    cycle();
    benchmark::ClobberMemory();
  }
  report_allocations(state, allocs.count());

  rtfuse::Snapshot s1;
  core->snapshot().load(s1);
  benchmark::DoNotOptimize(s1);
  const std::int64_t fused = s1.loop.measurements_fused - s0.loop.measurements_fused;
  // Each cycle fuses 4 measurements: odometry twist, IMU orientation, rates, accel.
  state.counters["fused_per_iter"] =
      benchmark::Counter(static_cast<double>(fused), benchmark::Counter::kAvgIterations);
  if (!s0.initialized || !s1.initialized) {
    state.SkipWithError("the filter never initialised");
  } else if (fused != 4 * static_cast<std::int64_t>(state.iterations())) {
    std::ostringstream why;
    why << "expected 4 fused measurements per tick, got " << fused << " in " << state.iterations()
        << " ticks (odom accepted " << s1.sensors[0].accepted << ", imu accepted " << s1.sensors[1].accepted
        << ", decode errors " << s1.sensors[0].decode_errors + s1.sensors[1].decode_errors << ")";
    state.SkipWithError(why.str().c_str());
  }
}
BENCHMARK(BM_LoopTick);

// A flood on the IMU channel (issue 11, "Inputs from the network"): 1000
// valid-looking messages per 20 ms period, 50 kHz, from a sender on the LCM
// group. With max_rate at what the loop drains (2 x queue_size x 50 Hz =
// 1000 Hz), the LCM thread drops the excess before decoding; the loop's
// tick, timed alone, fuses at most the ring's 20 per sensor.
void BM_LoopTickUnderFlood(benchmark::State& state) {
  rtfuse::RuntimeConfig cfg = jackal_config();
  for (int i = 0; i < cfg.num_sensors; ++i) {
    cfg.sensors[i].max_rate_hz = 2.0 * cfg.sensors[i].params.queue_size * cfg.rate_hz;
  }
  std::unique_ptr<rtfuse::FusionCore> core = create_core(state, cfg);
  if (!core) return;
  std::vector<std::uint8_t> odom = encoded_odometry();
  std::vector<std::uint8_t> imu = encoded_imu();
  const int odom_size = static_cast<int>(odom.size());
  const int imu_size = static_cast<int>(imu.size());
  constexpr std::int64_t kPeriodUs = 20'000;
  constexpr int kFlood = 1000;
  std::int64_t t_us = 1'000'000;
  rtfuse::LoopStats loop;
  loop.rate_hz = 50.0;
  loop.period_ns = 20'000'000;
  auto flood = [&]() {
    for (int k = 0; k < kFlood; ++k) {
      const std::int64_t at = t_us + k * kPeriodUs / kFlood;
      patch_utime(imu.data(), at);
      core->input().on_message("imu", imu.data(), imu_size, rtfuse::utime_to_ns(at));
    }
    patch_utime(odom.data(), t_us + kPeriodUs / 2);
    core->input().on_message("odom", odom.data(), odom_size, rtfuse::utime_to_ns(t_us + kPeriodUs / 2));
  };
  auto tick = [&]() {
    ++loop.ticks;
    core->tick(rtfuse::utime_to_ns(t_us + kPeriodUs), loop);
    t_us += kPeriodUs;
  };
  for (int i = 0; i < 20; ++i) {
    flood();
    tick();
  }
  rtfuse::Snapshot s0;
  core->snapshot().load(s0);
  AllocScope allocs;
  for (auto _ : state) {
    flood();
    const auto start = std::chrono::steady_clock::now();
    tick();
    const auto end = std::chrono::steady_clock::now();
    state.SetIterationTime(std::chrono::duration<double>(end - start).count());
  }
  report_allocations(state, allocs.count());
  rtfuse::Snapshot s1;
  core->snapshot().load(s1);
  const auto per_tick = [&](std::int64_t a, std::int64_t b) {
    return benchmark::Counter(static_cast<double>(b - a), benchmark::Counter::kAvgIterations);
  };
  state.counters["imu_fused_per_tick"] = per_tick(s0.sensors[1].accepted, s1.sensors[1].accepted);
  state.counters["imu_rate_limited_per_tick"] = per_tick(s0.sensors[1].rejected_rate, s1.sensors[1].rejected_rate);
  state.counters["imu_overflow_per_tick"] = per_tick(s0.sensors[1].rejected_overflow, s1.sensors[1].rejected_overflow);
}
BENCHMARK(BM_LoopTickUnderFlood)->UseManualTime();

// What one flooding message costs the LCM thread once the rate limit drops
// it (a channel compare and the limiter), against decoding it.
void BM_InputMessage(benchmark::State& state) {
  const bool limited = state.range(0) != 0;
  rtfuse::RuntimeConfig cfg = jackal_config();
  cfg.sensors[1].max_rate_hz = limited ? 1.0 : 0.0;  // 0: no limit
  std::unique_ptr<rtfuse::FusionCore> core = create_core(state, cfg);
  if (!core) return;
  std::vector<std::uint8_t> imu = encoded_imu();
  const int imu_size = static_cast<int>(imu.size());
  rtfuse::TimeNs now = 1'000'000'000;
  // Fill the burst allowance and the ring first: from then on every
  // message is dropped, by the limiter or (unlimited) as overflow after its
  // decode.
  for (int i = 0; i < 100; ++i) core->input().on_message("imu", imu.data(), imu_size, now);
  for (auto _ : state) {
    ++now;
    benchmark::DoNotOptimize(core->input().on_message("imu", imu.data(), imu_size, now));
  }
  state.SetLabel(limited ? "dropped by max_rate" : "decoded, then ring full");
}
BENCHMARK(BM_InputMessage)->Arg(1)->Arg(0);

// ---------------------------------------------------------------------------
// The shared Jackal bag, end to end

struct Bag2 {
  bool ok = false;
  std::string error;
  std::filesystem::path dir;
  std::string log_path;
  std::unique_ptr<rtfuse::RuntimeConfig> config;
  double log_seconds = 0.0;

  Bag2() = default;
  Bag2(const Bag2&) = delete;
  Bag2& operator=(const Bag2&) = delete;
  ~Bag2() {
    std::error_code ec;
    if (!dir.empty()) std::filesystem::remove_all(dir, ec);
  }
};

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  std::string t = s.str();
  if (t.size() > 1500) t = "..." + t.substr(t.size() - 1500);
  return t;
}

// Converts the bag and the parameters once per process, with the project's tools.
void load_bag2(Bag2& r) {
  namespace fs = std::filesystem;
  const fs::path shared = fs::path(RTFUSE_SHARED_DATA) / "robot_localization";
  const fs::path bag = shared / "test2.bag";
  const fs::path params = shared / "test_ekf_localization_node_bag2.yaml";
  if (!fs::is_regular_file(bag) || !fs::is_regular_file(params)) {
    r.error = "shared Jackal data missing: need " + bag.string() + " and " + params.string() +
              " (set -DRTFUSE_SHARED_DATA=<folder holding robot_localization/>)";
    return;
  }
  const fs::path src = RTFUSE_SOURCE_DIR;
  const fs::path python_types = fs::path(RTFUSE_BINARY_DIR) / "lcmtypes" / "python";
  std::string tmpl = (fs::temp_directory_path() / "rtfuse_bench.XXXXXX").string();
  if (mkdtemp(tmpl.data()) == nullptr) {
    r.error = "mkdtemp failed for " + tmpl;
    return;
  }
  r.dir = tmpl;
  r.log_path = (r.dir / "test2.lcm").string();
  const fs::path toml = r.dir / "bag2.toml";
  const fs::path out = r.dir / "convert.out";
  setenv("RTFUSE_LCMTYPES_PYTHON", python_types.c_str(), 1);
  const std::string convert_bag = "/usr/bin/python3 '" + (src / "tools" / "rosbag_to_lcm.py").string() + "' '" +
                                  bag.string() + "' '" + r.log_path + "' >'" + out.string() + "' 2>&1";
  if (std::system(convert_bag.c_str()) != 0) {
    r.error = "tools/rosbag_to_lcm.py failed (needs python3-rosbag and " + python_types.string() +
              "): " + read_text(out);
    return;
  }
  const std::string convert_params = "/usr/bin/python3 '" + (src / "tools" / "rl_params_to_toml.py").string() +
                                     "' '" + params.string() + "' -o '" + toml.string() + "' >'" +
                                     out.string() + "' 2>&1";
  if (std::system(convert_params.c_str()) != 0) {
    r.error = "tools/rl_params_to_toml.py failed: " + read_text(out);
    return;
  }
  rtfuse::ConfigLoadResult loaded = rtfuse::load_config_file(toml.string());
  if (!loaded.ok()) {
    r.error = "converted config rejected: " +
              (loaded.errors.empty() ? std::string("?") : loaded.errors.front().to_string());
    return;
  }
  r.config = std::make_unique<rtfuse::RuntimeConfig>(std::move(*loaded.config));

  // The log's own span (first to last event), for the realtime factor.
  rtfuse::transport::EventLogReader in;
  std::string err;
  if (!in.open(r.log_path, &err)) {
    r.error = "converted log: " + err;
    return;
  }
  rtfuse::transport::LogEvent ev;
  std::int64_t first = 0, last = 0;
  bool any = false;
  rtfuse::transport::ReadStatus st;
  while ((st = in.next(&ev, &err)) == rtfuse::transport::ReadStatus::kEvent) {
    if (!any) first = ev.timestamp_us;
    last = ev.timestamp_us;
    any = true;
  }
  if (st == rtfuse::transport::ReadStatus::kError || !any) {
    r.error = "converted log unreadable or empty: " + err;
    return;
  }
  r.log_seconds = static_cast<double>(last - first) * 1e-6;
  r.ok = true;
}

const Bag2& bag2() {
  static Bag2 b;
  static const bool loaded = (load_bag2(b), true);
  (void)loaded;
  return b;
}

void BM_ReplayBag2(benchmark::State& state) {
  const Bag2& b = bag2();
  if (!b.ok) {
    state.SkipWithError(("BM_ReplayBag2 skipped: " + b.error).c_str());
    return;
  }
  rtfuse::ReplayResult last;
  std::string error;
  double wall_s = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    std::unique_ptr<rtfuse::Replay> replay = rtfuse::Replay::create(*b.config, &error);
    rtfuse::transport::EventLogReader in;
    if (!replay || !in.open(b.log_path, &error)) {
      state.SkipWithError(("replay set-up failed: " + error).c_str());
      break;
    }
    last = replay->run(in, nullptr, {});
    benchmark::DoNotOptimize(last);
    if (!last.ok) {
      state.SkipWithError(("replay failed: " + last.error).c_str());
      break;
    }
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // Seconds of recording per second of wall time (dimensionless).
  if (state.iterations() > 0 && wall_s > 0.0) {
    state.counters["realtime_factor"] = b.log_seconds / (wall_s / static_cast<double>(state.iterations()));
  }
  state.counters["log_s"] = b.log_seconds;
  state.counters["events"] = static_cast<double>(last.events);
  state.counters["ticks"] = static_cast<double>(last.ticks);
  state.counters["final_x"] = last.final.state[0];
  state.counters["final_y"] = last.final.state[1];
  state.counters["final_z"] = last.final.state[2];
}
BENCHMARK(BM_ReplayBag2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
