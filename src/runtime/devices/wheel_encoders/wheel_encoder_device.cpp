#include "runtime/devices/wheel_encoders/wheel_encoder_device.hpp"

#include <cmath>

#include "runtime/devices/device_registry.hpp"

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

}  // namespace

const char* const kCanBusKeys[7] = {"frames_received", "syncs_sent",   "send_failures", "malformed_frames",
                                    "unexpected_cob_ids", "error_frames", "bus_off_events"};
const char* const kEncoderNodeKeys[10] = {"counts",         "tpdos",         "heartbeats",   "emcy",
                                          "last_emcy_code", "silent_events", "stuck_events", "jump_events",
                                          "recoveries",     "nmt_starts"};
const char* const kWheelOdometryKeys[3] = {"twists", "no_side", "reseeds"};

drivers::CanopenEncodersConfig encoder_driver_config(const RuntimeConfig& cfg) {
  const CanSection& can = cfg.hardware.can;
  const WheelOdometrySection& w = cfg.hardware.wheel_odometry;
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
    const CanNodeSection& n = can.nodes[static_cast<std::size_t>(i)];
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
  const CanSection& can = cfg.hardware.can;
  const WheelOdometrySection& w = cfg.hardware.wheel_odometry;
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
    const CanNodeSection& n = can.nodes[static_cast<std::size_t>(i)];
    drivers::WheelConfig& wc = d.wheels[static_cast<std::size_t>(i)];
    wc.encoder_index = i;
    wc.side = n.side == WheelSideConfig::kLeft ? drivers::WheelSide::kLeft : drivers::WheelSide::kRight;
    wc.sign = n.sign;
  }
  return d;
}

WheelEncoderDevice::WheelEncoderDevice(FusionCore& core, int first_slot)
    : cfg_(core.config()), core_(core), first_slot_(first_slot), sensor_(source_sensor(core.config(), "wheel_odometry")) {}

std::unique_ptr<WheelEncoderDevice> WheelEncoderDevice::create(hal::CanBus& bus, FusionCore& core, int first_slot,
                                                               std::string* error) {
  const RuntimeConfig& cfg = core.config();
  std::unique_ptr<WheelEncoderDevice> d(new WheelEncoderDevice(core, first_slot));
  d->encoders_ = drivers::CanopenEncoders::create(bus, encoder_driver_config(cfg), error);
  if (!d->encoders_) return nullptr;
  if (d->sensor_ >= 0) {
    d->wheels_ = drivers::WheelOdometry::create(wheel_driver_config(cfg), error);
    if (!d->wheels_) return nullptr;
  }
  // Samples of driver-fed sensors are in base_link.
  d->sample_.sensor = static_cast<std::uint8_t>(d->sensor_ < 0 ? 0 : d->sensor_);
  d->sample_.kind = est::SensorKind::kTwist;
  d->sample_.frame = static_cast<std::int16_t>(core.frames().find(cfg.base_link_frame.view()));
  return d;
}

bool WheelEncoderDevice::start(TimeNs now, std::string* error) {
  if (encoders_->start(now)) return true;
  *error = std::string("CAN encoders: NMT start failed: ") + encoders_->last_error();
  return false;
}

void WheelEncoderDevice::poll(TimeNs now) noexcept {
  encoders_->poll(now);
  drivers::EncoderSampleSet set;
  if (!wheels_ || !encoders_->take_sample_set(&set)) return;
  drivers::WheelTwist tw;
  if (!wheels_->update(set.readings, set.node_count, &tw)) return;
  last_twist_ = tw;
  have_twist_ = true;
  est::SensorSample& s = sample_;
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
  core_.input().push_from_driver(sensor_, s);
}

void WheelEncoderDevice::fill_snapshot(Snapshot& s) noexcept {
  const drivers::CanopenBusStats& b = encoders_->bus_stats();
  DeviceStatus& bus = s.devices[first_slot_];
  set_device_values(bus, kCanBusKeys,
                    {b.frames_received, b.syncs_sent, b.send_failures, b.malformed_frames, b.unexpected_cob_ids,
              b.error_frames, b.bus_off_events});
  set_device_message(bus.message, encoders_->last_error());
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
    DeviceStatus& d = s.devices[first_slot_ + 1 + i];
    set_device_values(d, kEncoderNodeKeys,
                      {r.counts, n.tpdos, n.heartbeats, n.emcys, n.last_emcy_code, n.silent_events, n.stuck_events,
                n.jump_events, n.recoveries, n.nmt_starts});
    d.level = encoder_level(r.health);
    d.state = drivers::to_string(r.health);
    set_device_message(d.message, encoders_->node_error(i));
  }
  if (wheels_) {
    const drivers::WheelOdometryStats& w = wheels_->stats();
    DeviceStatus& d = s.devices[first_slot_ + 1 + encoders_->node_count()];
    set_device_values(d, kWheelOdometryKeys, {w.outputs, w.no_side, w.reseeds});
    d.level = w.outputs == 0 ? DeviceLevel::kStale : DeviceLevel::kOk;
    d.state = w.outputs == 0 ? "waiting" : "running";
    // Its failures are its inputs': the nodes say what they were.
    d.message = DeviceMessage();
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

}  // namespace rtfuse
