#include "runtime/devices/imu/imu_device.hpp"

#include <cmath>

#include "runtime/devices/device_registry.hpp"

namespace rtfuse {

const char* const kImuKeys[13] = {"samples",   "reads",     "nacks",          "bus_errors",       "timeouts",
                                  "frozen",    "saturated", "impossible",     "missing_edges",    "out_of_order_edges",
                                  "reinits",   "filter_rejects", "temperature_mdegc"};

bool imu_driver_config(const RuntimeConfig& cfg, const geometry::FrameTree& frames, drivers::MpuImuConfig* out,
                       std::string* error) {
  const MpuSection& m = cfg.hardware.mpu;
  drivers::MpuImuConfig d;
  d.chip.address = m.address;
  switch (m.model) {
    case MpuModelConfig::kAuto: d.chip.model = drivers::MpuModel::kAuto; break;
    case MpuModelConfig::kMpu6050: d.chip.model = drivers::MpuModel::kMpu6050; break;
    case MpuModelConfig::kMpu6500: d.chip.model = drivers::MpuModel::kMpu6500; break;
    case MpuModelConfig::kMpu9250: d.chip.model = drivers::MpuModel::kMpu9250; break;
  }
  d.chip.sample_rate_div = m.sample_rate_divider;
  d.chip.dlpf = m.dlpf;
  d.chip.gyro_full_scale_dps = m.gyro_range_dps;
  d.chip.accel_full_scale_g = m.accel_range_g;
  d.chip.frozen_reads = m.frozen_reads;
  const auto base_T_imu = frames.lookup(cfg.base_link_frame.view(), m.frame.view());
  if (!base_T_imu) {
    *error = "mpu.frame '" + std::string(m.frame.view()) + "' is not connected to '" +
             std::string(cfg.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
             std::string(cfg.base_link_frame.view()) + "' and child = '" + std::string(m.frame.view()) +
             "' (the IMU's mounting)";
    return false;
  }
  d.chip.base_R_imu = base_T_imu->rotation;
  d.attitude.algorithm = m.attitude.algorithm == AttitudeAlgorithmConfig::kMahony
                             ? drivers::AttitudeAlgorithm::kMahony
                             : drivers::AttitudeAlgorithm::kMadgwick;
  d.attitude.beta = m.attitude.beta;
  d.attitude.zeta = m.attitude.zeta;
  d.attitude.kp = m.attitude.kp;
  d.attitude.ki = m.attitude.ki;
  d.attitude.gravity = cfg.filter.gravity;
  d.stillness.enabled = m.attitude.stillness_bias;
  d.noise.gyro_variance = m.gyro_noise_rad_s * m.gyro_noise_rad_s;
  d.noise.accel_variance = m.accel_noise_mps2 * m.accel_noise_mps2;
  d.poll_rate_hz = m.data_ready_chip.empty() ? m.poll_rate_hz : 0.0;
  *out = d;
  return true;
}

ImuDevice::ImuDevice(FusionCore& core, int device_slot)
    : core_(core), sensor_(source_sensor(core.config(), "mpu")), slot_(device_slot) {}

std::unique_ptr<ImuDevice> ImuDevice::create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                             std::string* error) {
  if (buses.i2c == nullptr || buses.clock == nullptr) {
    *error = "[mpu] is configured but the HAL has no I2C bus";
    return nullptr;
  }
  drivers::MpuImuConfig icfg;
  if (!imu_driver_config(core.config(), core.frames(), &icfg, error)) return nullptr;
  std::unique_ptr<ImuDevice> d(new ImuDevice(core, device_slot));
  d->imu_ = std::make_unique<drivers::MpuImu>(icfg, *buses.i2c, buses.edge, *buses.clock);
  // Samples of driver-fed sensors are in base_link: the driver rotates.
  d->sample_.sensor = static_cast<std::uint8_t>(d->sensor_ < 0 ? 0 : d->sensor_);
  d->sample_.kind = est::SensorKind::kImu;
  d->sample_.frame = static_cast<std::int16_t>(core.frames().find(core.config().base_link_frame.view()));
  d->health_.store(d->scratch_);
  return d;
}

bool ImuDevice::start(TimeNs, std::string* error) {
  if (imu_->start()) return true;
  *error = std::string("IMU: ") + imu_->error();
  return false;
}

drivers::StepResult ImuDevice::step_imu(TimeNs timeout_ns) noexcept {
  const drivers::StepResult r = imu_->step(timeout_ns, &measurement_);
  Health& h = scratch_;
  if (r == drivers::StepResult::kSample) {
    const drivers::ImuMeasurement& m = measurement_;
    est::SensorSample& s = sample_;
    s.stamp = m.stamp;
    est::ImuSample& i = s.imu;
    i.has_orientation = m.has_orientation;
    i.has_angular_velocity = m.has_angular_velocity;
    i.has_linear_acceleration = m.has_linear_acceleration;
    i.orientation = m.orientation;
    i.orientation_covariance = m.orientation_cov;
    i.angular_velocity = m.angular_velocity;
    i.angular_velocity_covariance = m.angular_velocity_cov;
    i.linear_acceleration = m.linear_acceleration;
    i.linear_acceleration_covariance = m.linear_acceleration_cov;
    core_.input().push_from_driver(sensor_, s);
    samples_.fetch_add(1, std::memory_order_acq_rel);
    h.temperature_c = m.temperature_c;
    h.last_sample_ns = m.stamp;
  }
  h.last = r;
  h.stats = imu_->stats();
  const char* error = imu_->error();
  if (error[0] != '\0') set_device_message(h.error, error);
  health_.store(h);
  return r;
}

void ImuDevice::fill_snapshot(Snapshot& s) noexcept {
  if (slot_ < 0) return;
  Health h;
  health_.load(h);
  DeviceStatus& d = s.devices[slot_];
  const drivers::MpuImuStats& st = h.stats;
  set_device_values(d, kImuKeys,
                    {st.samples, st.reads, st.nacks, st.bus_errors + st.io_errors, st.timeouts, st.frozen,
                     st.saturated, st.impossible, st.missing_edges, st.out_of_order_edges, st.reinits,
                     st.filter_rejects, static_cast<std::int64_t>(std::lround(h.temperature_c * 1000.0))});
  d.state = drivers::to_string(h.last);
  d.message = h.error;
  switch (h.last) {
    case drivers::StepResult::kSample: d.level = DeviceLevel::kOk; break;
    case drivers::StepResult::kDown: d.level = st.samples == 0 ? DeviceLevel::kStale : DeviceLevel::kError; break;
    default: d.level = DeviceLevel::kWarn; break;
  }
}

}  // namespace rtfuse
