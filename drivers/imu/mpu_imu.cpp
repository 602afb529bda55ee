#include "drivers/imu/mpu_imu.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::drivers {

namespace {
// Edges stamped before the last one are dropped, but a single bogus stamp far
// in the future must not silence the line for good: after this many in a row
// the line's clock is taken as it now is.
constexpr int kOutOfOrderBeforeRebase = 5;
}  // namespace

const char* to_string(StepResult r) noexcept {
  switch (r) {
    case StepResult::kSample: return "sample";
    case StepResult::kTimeout: return "timeout";
    case StepResult::kDropped: return "dropped";
    case StepResult::kFault: return "fault";
    case StepResult::kReinitialised: return "reinitialised";
    case StepResult::kDown: return "down";
  }
  return "?";
}

MpuImu::MpuImu(const MpuImuConfig& config, hal::I2cBus& bus, hal::GpioEdgeSource* edges, hal::Clock& clock) noexcept
    : config_(config),
      driver_(bus, clock, config.chip),
      edges_(edges),
      clock_(clock),
      filter_(config.attitude, config.stillness),
      last_error_(error_.c_str()) {}

bool MpuImu::start() noexcept {
  started_ = true;
  if (!driver_.init(clock_.now())) {
    last_error_ = driver_.error();
    next_reinit_ = clock_.now() + config_.reinit_backoff_ns;
    return false;
  }
  after_init();
  return true;
}

void MpuImu::after_init() noexcept {
  const MpuModel model = driver_.model();
  noise_ = mpu_noise(config_.noise, model, config_.chip.dlpf, driver_.gyro_lsb_rad_s(), driver_.accel_lsb_mps2());
  filter_.set_noise(noise_.accel_variance, noise_.gyro_noise_density);
  // Per-axis variances are equal, so the rotation into base_link leaves them
  // as they are; it is applied anyway so unequal ones would stay correct.
  const Eigen::Matrix3d& r = driver_.base_R_imu();
  gyro_cov_ = r * (noise_.gyro_variance * Eigen::Matrix3d::Identity()) * r.transpose();
  accel_cov_ = r * (noise_.accel_variance * Eigen::Matrix3d::Identity()) * r.transpose();
  period_ns_ = driver_.sample_period_ns();
  poll_period_ns_ =
      config_.poll_rate_hz > 0 ? static_cast<TimeNs>(std::llround(1e9 / config_.poll_rate_hz)) : period_ns_;
  next_poll_ = 0;
  waited_ns_ = 0;
  consecutive_missing_ = 0;
}

StepResult MpuImu::reinit() noexcept {
  if (driver_.init(clock_.now())) {
    ++stats_.reinits;
    after_init();
    return StepResult::kReinitialised;
  }
  ++stats_.reinit_failures;
  last_error_ = driver_.error();
  next_reinit_ = clock_.now() + config_.reinit_backoff_ns;
  return StepResult::kDown;
}

StepResult MpuImu::while_down(TimeNs edge_timeout_ns) noexcept {
  const TimeNs now = clock_.now();
  if (now < next_reinit_) {
    // Wait as a timed-out edge would, so a caller's loop does not spin.
    clock_.sleep_until(std::min(next_reinit_, now + std::max<TimeNs>(edge_timeout_ns, 0)));
    if (clock_.now() < next_reinit_) return StepResult::kDown;
  }
  return reinit();
}

StepResult MpuImu::on_edge_timeout(TimeNs edge_timeout_ns) noexcept {
  ++stats_.edge_timeouts;
  waited_ns_ += std::max<TimeNs>(edge_timeout_ns, 0);
  const double limit = config_.missing_edge_periods * static_cast<double>(period_ns_);
  if (static_cast<double>(waited_ns_) <= limit) return StepResult::kTimeout;
  ++stats_.missing_edges;
  waited_ns_ = 0;
  if (++consecutive_missing_ < config_.missing_edges_before_reinit) return StepResult::kTimeout;
  error_.set("mpu at 0x%02x: %d missing data-ready edges in a row: re-initialising the chip",
             config_.chip.address, consecutive_missing_);
  last_error_ = error_.c_str();
  consecutive_missing_ = 0;
  return reinit();
}

bool MpuImu::next_stamp(TimeNs edge_timeout_ns, TimeNs* stamp, StepResult* result) noexcept {
  if (edges_ == nullptr) {
    const TimeNs now = clock_.now();
    // First poll, or behind by more than a period: restart the schedule from now.
    if (next_poll_ == 0 || next_poll_ + poll_period_ns_ < now) next_poll_ = now;
    next_poll_ += poll_period_ns_;
    clock_.sleep_until(next_poll_);
    *stamp = clock_.now();
    return true;
  }
  hal::GpioEdge edge;
  const hal::HalStatus s = edges_->wait_edge(edge_timeout_ns, &edge);
  if (s == hal::HalStatus::kTimeout) {
    *result = on_edge_timeout(edge_timeout_ns);
    return false;
  }
  if (s != hal::HalStatus::kOk) {
    ++stats_.edge_errors;
    error_.set("mpu data-ready line: %s (%s)", hal::to_string(s), edges_->last_error());
    last_error_ = error_.c_str();
    // A failing line returns at once; waiting out the timeout keeps the
    // caller's loop from spinning.
    clock_.sleep_until(clock_.now() + std::max<TimeNs>(edge_timeout_ns, 0));
    *result = StepResult::kFault;
    return false;
  }
  waited_ns_ = 0;
  consecutive_missing_ = 0;
  if (!edge.rising) {
    ++stats_.ignored_edges;
    *result = StepResult::kDropped;
    return false;
  }
  if (have_edge_ && edge.stamp <= last_edge_) {
    ++stats_.out_of_order_edges;
    if (++consecutive_out_of_order_ < kOutOfOrderBeforeRebase) {
      *result = StepResult::kDropped;
      return false;
    }
    have_sample_ = false;  // the filter's dt restarts from this edge
  }
  consecutive_out_of_order_ = 0;
  have_edge_ = true;
  last_edge_ = edge.stamp;
  *stamp = edge.stamp;
  return true;
}

StepResult MpuImu::step(TimeNs edge_timeout_ns, ImuMeasurement* out) noexcept {
  if (!driver_.initialised()) return while_down(edge_timeout_ns);
  TimeNs stamp = 0;
  StepResult result = StepResult::kTimeout;
  if (!next_stamp(edge_timeout_ns, &stamp, &result)) return result;

  ImuReading reading;
  const MpuReadStatus rs = driver_.read(stamp, &reading);
  if (rs == MpuReadStatus::kOk) return deliver(reading, out);
  if (rs == MpuReadStatus::kSaturated) return StepResult::kDropped;
  last_error_ = driver_.error();
  if (driver_.needs_reinit()) return reinit();
  return StepResult::kFault;
}

StepResult MpuImu::deliver(const ImuReading& r, ImuMeasurement* out) noexcept {
  const double dt = ns_to_sec(have_sample_ ? r.stamp - last_sample_ : period_ns_);
  const AttitudeUpdate u = filter_.update(r.gyro, r.accel, dt, !r.accel_saturated);
  const bool rejected = u == AttitudeUpdate::kRejectedNonFinite || u == AttitudeUpdate::kRejectedDt;
  if (rejected) {
    ++stats_.filter_rejects;
  } else {
    have_sample_ = true;
    last_sample_ = r.stamp;
  }
  if (u == AttitudeUpdate::kGapReinitialised) ++stats_.filter_gap_reinits;
  if (r.gyro_saturated && !rejected) {
    // The rate was beyond full scale by an unknown amount: at least another
    // full scale's worth of rotation over this sample is unaccounted for.
    const double unseen = driver_.gyro_full_scale_rad_s() * dt;
    filter_.inflate(unseen * unseen, unseen * unseen);
  }

  out->stamp = r.stamp;
  out->orientation = filter_.orientation();
  out->orientation_cov = filter_.orientation_covariance();
  out->has_orientation = filter_.initialised() && !rejected && !r.gyro_saturated;
  out->angular_velocity = r.gyro - filter_.gyro_bias();
  out->angular_velocity_cov = gyro_cov_;
  // The z bias is known only as well as the last standstill taught it, and
  // before any standstill only to the chip's start-up tolerance: nothing
  // else observes it, so its variance belongs in the reported yaw rate.
  out->angular_velocity_cov(2, 2) += filter_.yaw_rate_bias_variance();
  out->has_angular_velocity = !r.gyro_saturated;
  out->linear_acceleration = r.accel;
  out->linear_acceleration_cov = accel_cov_;
  out->has_linear_acceleration = !r.accel_saturated;
  out->temperature_c = r.temperature_c;
  ++stats_.samples;
  return StepResult::kSample;
}

MpuImuStats MpuImu::stats() const noexcept {
  MpuImuStats s = stats_;
  const MpuDriverStats& d = driver_.stats();
  s.reads = d.reads;
  s.nacks = d.nacks;
  s.bus_errors = d.bus_errors;
  s.timeouts = d.timeouts;
  s.io_errors = d.io_errors;
  s.frozen = d.frozen;
  s.saturated = d.saturated;
  s.impossible = d.impossible;
  return s;
}

const char* MpuImu::error() const noexcept { return last_error_; }

}  // namespace rtfuse::drivers
