#include "runtime/hardware.hpp"

#include <cmath>
#include <cstdio>
#include <initializer_list>

namespace rtfuse {
namespace {

// Variance given to twist components the wheels do not measure (vz, vroll,
// vpitch): "unknown", as diff_drive_controller reports them.
constexpr double kUnmeasuredVariance = 1e6;

DeviceLevel encoder_level(drivers::EncoderHealth h) noexcept {
  switch (h) {
    case drivers::EncoderHealth::kOk: return DeviceLevel::kOk;
    case drivers::EncoderHealth::kNotStarted: return DeviceLevel::kStale;
    case drivers::EncoderHealth::kNoSample: return DeviceLevel::kWarn;
    default: return DeviceLevel::kError;
  }
}

// Values in the order of the layout's keys (device_layout.cpp), so the
// names are written in one place only.
void set_values(DeviceStatus& d, const char* const* keys, int n, std::initializer_list<std::int64_t> values) noexcept {
  d.num_values = 0;
  int i = 0;
  for (std::int64_t v : values) {
    if (i == n) break;
    d.add(keys[i++], v);
  }
}

}  // namespace

drivers::CanopenEncodersConfig encoder_driver_config(const RuntimeConfig& cfg) {
  const CanConfig& can = cfg.hardware.can;
  const WheelOdometryConfig& w = cfg.hardware.wheel_odometry;
  drivers::CanopenEncodersConfig d;
  d.node_count = can.num_nodes;
  d.sync_cob_id = can.sync_cob_id;
  d.heartbeat_timeout_ns = sec_to_ns(can.heartbeat_timeout_s);
  d.tpdo_timeout_syncs = can.tpdo_timeout_syncs;
  d.stuck_time_ns = sec_to_ns(can.stuck_time_s);
  // The physical limit in counts: max wheel speed over the wheel
  // circumference, times the counts of one wheel turn.
  const double counts_per_m = w.counts_per_rev * w.gear_ratio / (2.0 * M_PI * w.wheel_radius_m);
  d.max_counts_per_s = can.max_wheel_speed_mps * counts_per_m;
  // "Another wheel moved" means more than 5 cm: less is a pivot or a nudge.
  d.stuck_min_counts = static_cast<std::int64_t>(std::ceil(0.05 * counts_per_m));
  for (int i = 0; i < can.num_nodes; ++i) {
    const WheelNodeConfig& n = can.nodes[static_cast<std::size_t>(i)];
    drivers::EncoderNodeConfig& e = d.nodes[static_cast<std::size_t>(i)];
    e.node_id = n.node_id;
    e.tpdo.cob_id = n.tpdo_cob_id;
    e.tpdo.byte_offset = n.position_offset;
    e.tpdo.width_bits = n.position_bits;
    e.tpdo.is_signed = n.position_signed;
  }
  return d;
}

drivers::WheelOdometryConfig wheel_driver_config(const RuntimeConfig& cfg) {
  const CanConfig& can = cfg.hardware.can;
  const WheelOdometryConfig& w = cfg.hardware.wheel_odometry;
  drivers::WheelOdometryConfig d;
  d.kinematics = w.kinematics == KinematicsConfig::kSkidSteer ? drivers::DriveKinematics::kSkidSteer
                                                              : drivers::DriveKinematics::kDifferential;
  d.track_width_m = w.track_width_m;
  d.wheel_radius_m = w.wheel_radius_m;
  d.counts_per_rev = w.counts_per_rev;
  d.gear_ratio = w.gear_ratio;
  d.skid_track_factor = w.skid_track_factor;
  d.vx_sigma_floor_mps = w.speed_noise_mps;
  d.vyaw_sigma_floor_radps = w.yaw_rate_noise_rad_s;
  d.slip_fraction = w.slip;
  d.wheel_count = can.num_nodes;
  for (int i = 0; i < can.num_nodes; ++i) {
    const WheelNodeConfig& n = can.nodes[static_cast<std::size_t>(i)];
    drivers::WheelConfig& wc = d.wheels[static_cast<std::size_t>(i)];
    wc.encoder_index = i;
    wc.side = n.side == WheelSideConfig::kLeft ? drivers::WheelSide::kLeft : drivers::WheelSide::kRight;
    wc.sign = n.sign;
  }
  return d;
}

bool imu_driver_config(const RuntimeConfig& cfg, const geometry::FrameTree& frames, drivers::MpuImuConfig* out,
                       std::string* error) {
  const MpuConfig& m = cfg.hardware.mpu;
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
  d.noise.gyro_variance = m.gyro_noise_rad_s * m.gyro_noise_rad_s;
  d.noise.accel_variance = m.accel_noise_mps2 * m.accel_noise_mps2;
  d.poll_rate_hz = m.data_ready_chip.empty() ? m.poll_rate_hz : 0.0;
  *out = d;
  return true;
}

Hardware::Hardware(const RuntimeConfig& cfg, FusionCore& core)
    : cfg_(cfg), core_(core), slots_(device_slots(cfg)) {
  describe_devices(cfg, layout_, kMaxDevices);
}

std::unique_ptr<Hardware> Hardware::create(const HalBuses& buses, FusionCore& core, std::string* error) {
  const RuntimeConfig& cfg = core.config();
  std::unique_ptr<Hardware> h(new Hardware(cfg, core));
  const HardwareConfig& hw = cfg.hardware;
  h->base_frame_ = core.frames().find(cfg.base_link_frame.view());
  if (hw.can.enabled) {
    if (buses.can == nullptr) {
      *error = "[can] is configured but the HAL has no CAN bus";
      return nullptr;
    }
    h->encoders_ = drivers::CanopenEncoders::create(*buses.can, encoder_driver_config(cfg), error);
    if (!h->encoders_) return nullptr;
    if (hw.wheel_sensor >= 0) {
      h->wheels_ = drivers::WheelOdometry::create(wheel_driver_config(cfg), error);
      if (!h->wheels_) return nullptr;
    }
  }
  if (hw.mpu.enabled) {
    if (buses.i2c == nullptr || buses.imu_clock == nullptr) {
      *error = "[mpu] is configured but the HAL has no I2C bus";
      return nullptr;
    }
    drivers::MpuImuConfig icfg;
    if (!imu_driver_config(cfg, core.frames(), &icfg, error)) return nullptr;
    h->imu_ = std::make_unique<drivers::MpuImu>(icfg, *buses.i2c, buses.drdy, *buses.imu_clock);
  }
  // Samples of driver-fed sensors are in base_link: the drivers rotate.
  h->wheel_sample_.sensor = static_cast<std::uint8_t>(hw.wheel_sensor < 0 ? 0 : hw.wheel_sensor);
  h->wheel_sample_.kind = est::SensorKind::kTwist;
  h->wheel_sample_.frame = static_cast<std::int16_t>(h->base_frame_);
  h->imu_sample_.sensor = static_cast<std::uint8_t>(hw.mpu_sensor < 0 ? 0 : hw.mpu_sensor);
  h->imu_sample_.kind = est::SensorKind::kImu;
  h->imu_sample_.frame = static_cast<std::int16_t>(h->base_frame_);
  h->imu_health_.store(h->imu_health_scratch_);
  return h;
}

bool Hardware::start(TimeNs now, std::string* error) {
  if (encoders_ && !encoders_->start(now)) {
    *error = std::string("CAN encoders: NMT start failed: ") + encoders_->last_error();
    return false;
  }
  if (imu_ && !imu_->start()) {
    *error = std::string("IMU: ") + imu_->error();
    return false;
  }
  return true;
}

void Hardware::before_drain(TimeNs now) noexcept {
  if (!encoders_) return;
  encoders_->poll(now);
  drivers::EncoderSampleSet set;
  if (!wheels_ || !encoders_->take_sample_set(&set)) return;
  drivers::WheelTwist tw;
  if (!wheels_->update(set.readings, set.node_count, &tw)) return;
  last_twist_ = tw;
  have_twist_ = true;
  est::SensorSample& s = wheel_sample_;
  s.stamp = tw.stamp;
  s.twist.linear = Eigen::Vector3d(tw.vx, 0.0, 0.0);
  s.twist.angular = Eigen::Vector3d(0.0, 0.0, tw.vyaw);
  est::Matrix6& c = s.twist.covariance;
  const double lateral = cfg_.hardware.wheel_odometry.lateral_noise_mps;
  c.setZero();
  c(0, 0) = tw.var_vx;
  c(1, 1) = lateral * lateral;
  c(2, 2) = c(3, 3) = c(4, 4) = kUnmeasuredVariance;
  c(5, 5) = tw.var_vyaw;
  c(0, 5) = c(5, 0) = tw.cov_vx_vyaw;
  // The loop is this ring's only producer.
  core_.input().push_from_driver(cfg_.hardware.wheel_sensor, s);
}

drivers::StepResult Hardware::imu_step(TimeNs edge_timeout_ns) noexcept {
  const drivers::StepResult r = imu_->step(edge_timeout_ns, &imu_measurement_);
  ImuHealth& h = imu_health_scratch_;
  if (r == drivers::StepResult::kSample) {
    const drivers::ImuMeasurement& m = imu_measurement_;
    est::SensorSample& s = imu_sample_;
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
    core_.input().push_from_driver(cfg_.hardware.mpu_sensor, s);
    imu_samples_.fetch_add(1, std::memory_order_acq_rel);
    h.temperature_c = m.temperature_c;
    h.last_sample_ns = m.stamp;
  }
  h.last = r;
  h.stats = imu_->stats();
  imu_health_.store(h);
  return r;
}

void Hardware::fill_snapshot(Snapshot& s) noexcept {
  s.num_devices = slots_.count;
  for (int i = 0; i < slots_.count; ++i) {
    s.devices[i].name = layout_[i].name;
    s.devices[i].hardware_id = layout_[i].hardware_id;
  }
  if (encoders_) fill_can(s);
  if (imu_) fill_imu(s);
}

void Hardware::fill_can(Snapshot& s) noexcept {
  const drivers::CanopenBusStats& b = encoders_->bus_stats();
  DeviceStatus& bus = s.devices[slots_.can_bus];
  set_values(bus, kCanBusKeys, kCanBusKeyCount,
             {b.frames_received, b.syncs_sent, b.send_failures, b.malformed_frames, b.unexpected_cob_ids,
              b.error_frames, b.bus_off_events});
  if (b.bus_off) {
    bus.level = DeviceLevel::kError;
    bus.state = "bus-off";
  } else if (b.bus_state == hal::CanBusState::kErrorPassive || b.bus_state == hal::CanBusState::kErrorWarning) {
    bus.level = DeviceLevel::kWarn;
    bus.state = b.bus_state == hal::CanBusState::kErrorPassive ? "error-passive" : "error-warning";
  } else if (b.frames_received == 0) {
    bus.level = DeviceLevel::kStale;
    bus.state = "no frames";
  } else {
    bus.level = DeviceLevel::kOk;
    bus.state = "error-active";
  }
  for (int i = 0; i < encoders_->node_count(); ++i) {
    const drivers::EncoderReading& r = encoders_->reading(i);
    const drivers::EncoderNodeStats& n = encoders_->node_stats(i);
    DeviceStatus& d = s.devices[slots_.first_node + i];
    set_values(d, kEncoderNodeKeys, kEncoderNodeKeyCount,
               {r.counts, n.tpdos, n.heartbeats, n.emcys, n.last_emcy_code, n.silent_events, n.stuck_events,
                n.jump_events, n.recoveries, n.nmt_starts});
    d.level = encoder_level(r.health);
    d.state = drivers::to_string(r.health);
  }
  if (wheels_ && slots_.wheel_odometry >= 0) {
    const drivers::WheelOdometryStats& w = wheels_->stats();
    DeviceStatus& d = s.devices[slots_.wheel_odometry];
    set_values(d, kWheelOdometryKeys, kWheelOdometryKeyCount, {w.outputs, w.no_side, w.reseeds});
    d.level = w.outputs == 0 ? DeviceLevel::kStale : DeviceLevel::kOk;
    d.state = w.outputs == 0 ? "waiting" : "running";
    if (have_twist_) {
      WheelOdometrySnapshot& o = s.wheel_odometry;
      o.valid = true;
      o.stamp_ns = wheels_->pose_stamp();
      o.x = wheels_->pose().x;
      o.y = wheels_->pose().y;
      o.yaw = wheels_->pose().yaw;
      o.vx = last_twist_.vx;
      o.vyaw = last_twist_.vyaw;
      o.var_vx = last_twist_.var_vx;
      o.var_vyaw = last_twist_.var_vyaw;
    }
  }
}

void Hardware::fill_imu(Snapshot& s) noexcept {
  ImuHealth h;
  imu_health_.load(h);
  DeviceStatus& d = s.devices[slots_.imu];
  const drivers::MpuImuStats& st = h.stats;
  set_values(d, kImuKeys, kImuKeyCount,
             {st.samples, st.reads, st.nacks, st.bus_errors + st.io_errors, st.timeouts, st.frozen, st.saturated,
              st.impossible, st.missing_edges, st.out_of_order_edges, st.reinits, st.filter_rejects,
              static_cast<std::int64_t>(std::lround(h.temperature_c * 1000.0))});
  d.state = drivers::to_string(h.last);
  switch (h.last) {
    case drivers::StepResult::kSample: d.level = DeviceLevel::kOk; break;
    case drivers::StepResult::kDown: d.level = st.samples == 0 ? DeviceLevel::kStale : DeviceLevel::kError; break;
    default: d.level = DeviceLevel::kWarn; break;
  }
}

}  // namespace rtfuse
