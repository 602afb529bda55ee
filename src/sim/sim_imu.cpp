#include "sim/sim_imu.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/physical_constants.hpp"
#include "geometry/rotation.hpp"
#include "sim/counter_rng.hpp"

namespace rtfuse::sim {

namespace {


// FS_SEL / AFS_SEL of a full-scale range, -1 if none matches.
int gyro_fs_sel(int dps) noexcept {
  return dps == 250 ? 0 : dps == 500 ? 1 : dps == 1000 ? 2 : dps == 2000 ? 3 : -1;
}
int accel_fs_sel(int g) noexcept { return g == 2 ? 0 : g == 4 ? 1 : g == 8 ? 2 : g == 16 ? 3 : -1; }

}  // namespace

SimImu::SimImu(const DriveScenario& scenario, TruthSource& truth, hal::Clock& clock, TimeNs t0)
    : truth_(truth),
      clock_(clock),
      t0_(t0),
      cfg_(scenario.imu),
      seed_(scenario.seed),
      period_ns_(1e9 / (scenario.imu.rate_hz > 0.0 ? scenario.imu.rate_hz : 1.0)),
      // White noise of density d sampled at f has sigma d * sqrt(f / 2): the
      // band up to Nyquist (the DLPF's band would be a refinement).
      gyro_sigma_(scenario.imu.gyro_noise_density * std::sqrt(0.5 * 1e9 / period_ns_)),
      accel_sigma_(scenario.imu.accel_noise_density * std::sqrt(0.5 * 1e9 / period_ns_)),
      half_track_m_(0.5 * scenario.robot.track_width_m),
      chip_(scenario.imu.model) {
  const Eigen::Matrix3d r = geometry::rotation_from_rpy(cfg_.rpy_rad[0], cfg_.rpy_rad[1], cfg_.rpy_rad[2]);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r_[i][j] = r(i, j);
  }
  bus_.attach(cfg_.address, chip_);
}

SimImu::~SimImu() { bus_.detach(cfg_.address); }

TimeNs SimImu::sample_time(std::int64_t k) const noexcept {
  return t0_ + static_cast<TimeNs>(std::llround(static_cast<double>(k) * period_ns_));
}

std::int64_t SimImu::first_sample_at_or_after(TimeNs t) const noexcept {
  if (t <= t0_) return 0;
  auto k = static_cast<std::int64_t>(std::ceil(static_cast<double>(t - t0_) / period_ns_));
  while (sample_time(k) < t) ++k;
  while (k > 0 && sample_time(k - 1) >= t) --k;
  return k;
}

ImuChipReading SimImu::ideal_sample(std::int64_t k) const noexcept {
  return reading_of(truth_.truth_at(ns_to_sec(sample_time(k) - t0_)));
}

ImuChipReading SimImu::reading_of(const TruthState& s) const noexcept {
  const double w = s.yaw_rate;
  const double dw = s.yaw_accel;
  const double px = cfg_.xyz_m[0];
  const double py = cfg_.xyz_m[1];
  // Specific force at the IMU's origin in base_link axes: the base's
  // acceleration, the lever arm's tangential (dw x p) and centripetal
  // (w x (w x p)) parts, and the floor pushing up against gravity.
  const double f[3] = {s.accel_body[0] - dw * py - w * w * px, s.accel_body[1] + dw * px - w * w * py,
                       s.accel_body[2] + kStandardGravity};
  const double rate[3] = {0.0, 0.0, w};
  ImuChipReading out;
  for (int i = 0; i < 3; ++i) {  // IMU axes: the transpose of base_link <- IMU
    out.accel_mps2[i] = r_[0][i] * f[0] + r_[1][i] * f[1] + r_[2][i] * f[2];
    out.gyro_rad_s[i] = r_[0][i] * rate[0] + r_[1][i] * rate[1] + r_[2][i] * rate[2];
  }
  out.temperature_c = cfg_.temperature_c;
  return out;
}

// The wheels shake the base in proportion to how fast they roll, so a turn
// on the spot shakes it as driving does; the fastest wheel of a
// differential or skid-steer base rolls at |v| + |w| * track / 2.
double SimImu::vibration_share(const TruthState& s) const noexcept {
  const double wheel_speed = std::abs(s.speed) + std::abs(s.yaw_rate) * half_track_m_;
  return std::min(1.0, wheel_speed / cfg_.vibration_speed_mps);
}

ImuChipReading SimImu::sample(std::int64_t k) const noexcept {
  const TruthState truth = truth_.truth_at(ns_to_sec(sample_time(k) - t0_));
  ImuChipReading s = reading_of(truth);
  const double shake = vibration_share(truth);
  const double gyro_shake = shake * cfg_.vibration_gyro_rad_s;
  const double accel_shake = shake * cfg_.vibration_accel_mps2;
  const auto index = static_cast<std::uint64_t>(k);
  for (int i = 0; i < 3; ++i) {
    const auto axis = static_cast<std::uint64_t>(i);
    s.gyro_rad_s[i] += cfg_.gyro_bias_rad_s[static_cast<std::size_t>(i)] +
                       gyro_sigma_ * counter_normal(seed_, stream::kGyro + axis, index);
    s.accel_mps2[i] += cfg_.accel_bias_mps2[static_cast<std::size_t>(i)] +
                       accel_sigma_ * counter_normal(seed_, stream::kAccel + axis, index);
    // Drawn only when there is vibration, so a vibration-free scenario's
    // samples stay what they were.
    if (gyro_shake > 0.0) s.gyro_rad_s[i] += gyro_shake * counter_normal(seed_, stream::kGyroVibration + axis, index);
    if (accel_shake > 0.0) {
      s.accel_mps2[i] += accel_shake * counter_normal(seed_, stream::kAccelVibration + axis, index);
    }
  }
  return s;
}

hal::HalStatus SimImu::wait_edge(TimeNs timeout_ns, hal::GpioEdge* out) noexcept {
  const TimeNs now = clock_.now();
  constexpr TimeNs kForever = std::numeric_limits<TimeNs>::max();
  const TimeNs wait = std::max<TimeNs>(timeout_ns, 0);
  const TimeNs deadline = wait > kForever - now ? kForever : now + wait;
  // A reader further behind than the kernel's event queue finds only the
  // most recent edges there; the older samples are gone.
  const std::int64_t oldest_kept = first_sample_at_or_after(now) - kEdgeQueue;
  if (next_ < oldest_kept) {
    skipped_ += oldest_kept - next_;
    next_ = oldest_kept;
  }
  // Bounded: one pass per sample period within the timeout.
  for (;;) {
    const TimeNs t = sample_time(next_);
    if (t > deadline) {
      clock_.sleep_until(deadline);
      return hal::HalStatus::kTimeout;
    }
    clock_.sleep_until(t);
    ImuChipReading s = sample(next_);
    for (int i = 0; i < 3; ++i) {
      s.accel_mps2[i] += disturbance_accel_[i];
      s.gyro_rad_s[i] += disturbance_gyro_[i];
    }
    ++next_;
    if (chip_.set_sample(s.accel_mps2, s.gyro_rad_s, s.temperature_c)) {
      if (edges_lost_) {
        ++lost_edges_;
        continue;
      }
      ++edges_;
      if (out != nullptr) *out = hal::GpioEdge{t, true};
      return hal::HalStatus::kOk;
    }
  }
}

void SimImu::set_disturbance(const double accel_mps2[3], const double gyro_rad_s[3]) noexcept {
  for (int i = 0; i < 3; ++i) {
    disturbance_accel_[i] = accel_mps2[i];
    disturbance_gyro_[i] = gyro_rad_s[i];
  }
}

hal::HalStatus SimImu::read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept {
  return bus_.read_registers(address, reg, buf, n);
}

hal::HalStatus SimImu::write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept {
  return bus_.write_register(address, reg, value);
}

const char* SimImu::config_mismatch() const noexcept {
  if (std::abs(chip_.sample_rate_hz() - cfg_.rate_hz) > 1e-6 * cfg_.rate_hz) {
    return "the driver set a sample rate (SMPLRT_DIV, DLPF_CFG) other than the scenario's imu.rate_hz";
  }
  if (chip_.gyro_fs_sel() != gyro_fs_sel(cfg_.gyro_range_dps)) {
    return "the driver set a gyro full scale other than the scenario's imu.gyro_range_dps";
  }
  if (chip_.accel_fs_sel() != accel_fs_sel(cfg_.accel_range_g)) {
    return "the driver set an accelerometer full scale other than the scenario's imu.accel_range_g";
  }
  return nullptr;
}

void SimImu::provide(DeviceBuses& out, hal::Clock& clock) noexcept {
  out.i2c = this;
  out.edge = this;
  out.clock = &clock;
}

std::unique_ptr<SimDevice> make_sim_imu(const SimDeviceContext& ctx, std::string* error) {
  const MpuSection& m = ctx.cfg.hardware.mpu;
  if (m.address != ctx.scenario.imu.address) {
    *error = ctx.cfg.source + ": mpu.address = " + std::to_string(m.address) + " but the simulated IMU in " +
             ctx.scenario_path + " answers at " + std::to_string(ctx.scenario.imu.address);
    return nullptr;
  }
  return std::make_unique<SimImu>(ctx.scenario, ctx.truth, ctx.clock, ctx.t0);
}

}  // namespace rtfuse::sim
