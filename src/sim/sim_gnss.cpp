#include "sim/sim_gnss.hpp"

#include <cmath>
#include <cstring>

#include "sim/counter_rng.hpp"

namespace rtfuse::sim {
namespace {

void put_u4(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_i4(std::uint8_t* p, std::int64_t v) noexcept { put_u4(p, static_cast<std::uint32_t>(v)); }

// NAV-PVT as the u-blox interface description lays it out (92 bytes).
constexpr int kPayload = 92;
constexpr int kFrame = kPayload + 8;

}  // namespace

SimGnss::SimGnss(const DriveScenario& scenario, TruthSource& truth, hal::Clock& clock, TimeNs t0)
    : cfg_(scenario.gnss),
      truth_(truth),
      clock_(clock),
      t0_(t0),
      seed_(scenario.seed),
      period_ns_(static_cast<TimeNs>(std::llround(1e9 / scenario.gnss.rate_hz))),
      latency_ns_(sec_to_ns(scenario.gnss.latency_s)),
      port_(clock, hal::mock::MockSerialPortCapacity{16 * kFrame, 4096}) {
  plane_.reset({cfg_.latitude_deg, cfg_.longitude_deg, cfg_.altitude_m});
}

TimeNs SimGnss::next_arrival() const noexcept {
  if (port_.pending() > 0) return clock_.now();
  return t0_ + next_ * period_ns_ + latency_ns_;
}

bool SimGnss::in_outage(double t_s) const noexcept {
  for (int i = 0; i < cfg_.outage_count; ++i) {
    const GnssOutage& o = cfg_.outages[static_cast<std::size_t>(i)];
    if (t_s >= o.start_s && t_s < o.start_s + o.duration_s) return true;
  }
  return false;
}

const SimGnssEpoch& SimGnss::epoch(std::int64_t k) noexcept {
  const double a = std::exp(-1.0 / (cfg_.rate_hz * cfg_.bias_time_s));
  const double b = std::sqrt(1.0 - a * a);
  const double sigma[3] = {cfg_.bias_sigma_m, cfg_.bias_sigma_m, cfg_.vertical_bias_sigma_m};
  const double p_jump = cfg_.multipath_per_hour / 3600.0 / cfg_.rate_hz;
  while (state_epoch_ < k) {
    const auto i = static_cast<std::uint64_t>(++state_epoch_);
    for (int axis = 0; axis < 3; ++axis) {
      const double n = counter_normal(seed_, stream::kGnss + static_cast<std::uint64_t>(axis), i);
      // Epoch 0 draws from the stationary distribution.
      bias_[axis] = state_epoch_ == 0 ? sigma[axis] * n : a * bias_[axis] + b * sigma[axis] * n;
    }
    if (multipath_left_ == 0 && counter_uniform(seed_, stream::kGnss + 6, i) < p_jump) {
      multipath_left_ = cfg_.multipath_epochs;
      const double angle = 6.283185307179586 * counter_uniform(seed_, stream::kGnss + 7, i);
      multipath_dir_[0] = std::cos(angle);
      multipath_dir_[1] = std::sin(angle);
    }
    const bool multipath = multipath_left_ > 0;
    if (multipath) --multipath_left_;
    SimGnssEpoch& e = current_;
    e.epoch = t0_ + state_epoch_ * period_ns_;
    e.arrival = e.epoch + latency_ns_;
    const double t = static_cast<double>(state_epoch_) / cfg_.rate_hz;
    const TruthState s = truth_.truth_at(t);
    const double c = std::cos(s.yaw), sn = std::sin(s.yaw);
    const auto& m = cfg_.antenna_xyz_m;
    e.truth_enu[0] = s.x + c * m[0] - sn * m[1];
    e.truth_enu[1] = s.y + sn * m[0] + c * m[1];
    e.truth_enu[2] = m[2];
    e.fix = !in_outage(t);
    e.multipath = multipath;
    const double noise[3] = {cfg_.noise_m, cfg_.noise_m, cfg_.vertical_noise_m};
    for (int axis = 0; axis < 3; ++axis) {
      e.error_enu[axis] =
          bias_[axis] + noise[axis] * counter_normal(seed_, stream::kGnss + 3 + static_cast<std::uint64_t>(axis), i);
    }
    if (e.multipath) {
      e.error_enu[0] += cfg_.multipath_m * multipath_dir_[0];
      e.error_enu[1] += cfg_.multipath_m * multipath_dir_[1];
    }
  }
  return current_;
}

void SimGnss::send(std::int64_t k) noexcept {
  const SimGnssEpoch& e = epoch(k);
  std::uint8_t* f = frame_;
  std::memset(f, 0, sizeof frame_);
  f[0] = 0xB5;
  f[1] = 0x62;
  f[2] = 0x01;  // NAV
  f[3] = 0x07;  // PVT
  f[4] = kPayload;
  f[5] = 0;
  std::uint8_t* p = f + 6;
  // UTC from the drive's start at 12:00:00 (only the time of day is used).
  const std::int64_t ms = 12 * 3'600'000 + (e.epoch - t0_) / 1'000'000;
  put_u4(p + 0, static_cast<std::uint32_t>(ms % 604'800'000));  // iTOW
  p[8] = static_cast<std::uint8_t>(ms / 3'600'000 % 24);
  p[9] = static_cast<std::uint8_t>(ms / 60'000 % 60);
  p[10] = static_cast<std::uint8_t>(ms / 1000 % 60);
  p[11] = 0x07;  // valid date, time, fully resolved
  put_i4(p + 16, (ms % 1000) * 1'000'000);  // nano
  const Eigen::Vector3d enu(e.truth_enu[0] + e.error_enu[0], e.truth_enu[1] + e.error_enu[1],
                            e.truth_enu[2] + e.error_enu[2]);
  const est::GeodeticPosition g = plane_.reverse(enu);
  p[20] = e.fix ? 3 : 0;           // fixType: 3-D, or none
  p[21] = e.fix ? 0x01 : 0x00;     // gnssFixOK
  p[23] = static_cast<std::uint8_t>(e.fix ? cfg_.satellites : 0);
  put_i4(p + 24, std::llround(g.longitude_deg * 1e7));
  put_i4(p + 28, std::llround(g.latitude_deg * 1e7));
  put_i4(p + 32, std::llround(g.altitude_m * 1e3));
  put_i4(p + 36, std::llround(g.altitude_m * 1e3));  // hMSL: the simulated earth has no geoid
  // What the receiver believes its accuracy is: bias and noise together
  // (it knows nothing of the multipath).
  const double h_acc = std::sqrt(cfg_.bias_sigma_m * cfg_.bias_sigma_m + cfg_.noise_m * cfg_.noise_m);
  const double v_acc =
      std::sqrt(cfg_.vertical_bias_sigma_m * cfg_.vertical_bias_sigma_m + cfg_.vertical_noise_m * cfg_.vertical_noise_m);
  put_u4(p + 40, static_cast<std::uint32_t>(std::llround((e.fix ? h_acc : 1e4) * 1e3)));
  put_u4(p + 44, static_cast<std::uint32_t>(std::llround((e.fix ? v_acc : 1e4) * 1e3)));
  std::uint8_t ca = 0, cb = 0;
  for (int i = 2; i < 6 + kPayload; ++i) {
    ca = static_cast<std::uint8_t>(ca + f[i]);
    cb = static_cast<std::uint8_t>(cb + ca);
  }
  f[6 + kPayload] = ca;
  f[7 + kPayload] = cb;
  port_.feed(f, kFrame, e.arrival);
}

int SimGnss::read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, hal::HalStatus* status) noexcept {
  const TimeNs now = clock_.now();
  const TimeNs deadline = now + (timeout_ns > 0 ? timeout_ns : 0);
  while (t0_ + next_ * period_ns_ + latency_ns_ <= deadline) send(next_++);
  return port_.read(out, max, timeout_ns, stamp, status);
}

hal::HalStatus SimGnss::write(const std::uint8_t* data, int size) noexcept {
  hal::HalStatus st = port_.write(data, size);
  port_.clear_written();
  return st;
}

void SimGnss::provide(DeviceBuses& out, hal::Clock& clock) noexcept {
  out.serial = this;
  out.clock = &clock;
}

std::unique_ptr<SimDevice> make_sim_gnss(const SimDeviceContext& ctx, std::string* error) {
  if (!ctx.scenario.gnss.enabled) {
    *error = ctx.cfg.source + ": [gnss] is configured but the scenario " + ctx.scenario_path +
             " has no [gnss] receiver on the simulated robot";
    return nullptr;
  }
  if (ctx.cfg.hardware.gnss.protocol != GnssProtocolConfig::kUbx) {
    *error = ctx.cfg.source + ": gnss.protocol: the simulated receiver speaks ubx (u-blox NAV-PVT)";
    return nullptr;
  }
  return std::make_unique<SimGnss>(ctx.scenario, ctx.truth, ctx.clock, ctx.t0);
}

}  // namespace rtfuse::sim
