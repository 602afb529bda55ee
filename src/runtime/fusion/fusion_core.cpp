#include "runtime/fusion/fusion_core.hpp"

#include <cmath>
#include <cstdio>

#include "geometry/rotation.hpp"
#include "runtime/fusion/navsat_status.hpp"
#include "runtime/fusion/standstill_status.hpp"

namespace rtfuse {

std::unique_ptr<FusionCore> FusionCore::create(const RuntimeConfig& cfg, std::string* error) {
  std::unique_ptr<FusionCore> core(new FusionCore(cfg));
  if (!core->build_frames(error)) return nullptr;
  if (!core->configure_navsat(error)) return nullptr;
  core->input_ = std::make_unique<InputRouter>(core->cfg_, core->frames_);
  return core;
}

FusionCore::FusionCore(const RuntimeConfig& cfg) : cfg_(cfg) {
  num_instances_ = cfg_.num_instances < 1 ? 1 : (cfg_.num_instances > kMaxInstances ? kMaxInstances : cfg_.num_instances);
  for (int k = 0; k < num_instances_; ++k) {
    instances_[k].filter = std::make_unique<est::Filter>(instance_filter(cfg_, k));
  }
  int absolute_yaw_sources[kMaxInstances] = {};
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    const SensorConfig& c = cfg_.sensors[i];
    const int k = c.instance < num_instances_ ? c.instance : 0;
    models_[i] = est::SensorModel(static_cast<std::uint8_t>(i), c.params, instance_filter(cfg_, k));
    if (models_[i].fuses_absolute_yaw()) ++absolute_yaw_sources[k];
    fused_by_[sensor_input(cfg_, i)] |= 1u << i;
    // A shared input's ring is its first sensor's: staged once.
    if (sensor_input(cfg_, i) == i) staging_capacity_ += 2 * c.params.queue_size;
  }
  // One absolute yaw source cannot conflict with anything; two can, and then
  // robot_localization would pull the estimate back and forth between them.
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    const int k = cfg_.sensors[i].instance < num_instances_ ? cfg_.sensors[i].instance : 0;
    if (absolute_yaw_sources[k] >= 2) models_[i].set_yaw_gate(instance_filter(cfg_, k).yaw_conflict_gate_sigma);
  }
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    const SensorConfig& c = cfg_.sensors[i];
    if (c.standstill_sensor < 0 || c.params.kind != est::SensorKind::kImu) continue;
    standstill_[i] = std::make_unique<est::StandstillGyroBias>(c.standstill);
    standstill_targets_[sensor_input(cfg_, c.standstill_sensor)] |= 1u << i;
    if (num_standstill_ < kMaxStandstillLearners) standstill_sensor_[num_standstill_++] = i;
  }
  if (num_standstill_ > 0) describe_standstill(cfg_, standstill_layout_);
  staging_ = std::make_unique<est::SensorSample[]>(static_cast<std::size_t>(staging_capacity_ > 0 ? staging_capacity_ : 1));
}

bool FusionCore::build_frames(std::string* error) {
  frames_.intern(cfg_.world_frame.view());
  frames_.intern(cfg_.odom_frame.view());
  frames_.intern(cfg_.map_frame.view());
  frames_.intern(cfg_.base_link_frame.view());
  for (int i = 0; i < cfg_.num_static_transforms; ++i) {
    const StaticTransformConfig& t = cfg_.static_transforms[i];
    std::string why;
    if (!frames_.add(t.parent.view(), t.child.view(), t.parent_T_child, &why)) {
      *error = cfg_.source + ": static_transform[" + std::to_string(i) + "]: " + why;
      return false;
    }
  }
  for (int k = 0; k < num_instances_; ++k) {
    Instance& in = instances_[k];
    const Name& world = instance_world_frame(cfg_, k);
    in.frames.tree = &frames_;
    in.frames.world = frames_.find(world.view());
    in.frames.base_link = frames_.find(cfg_.base_link_frame.view());
    in.in_map = world == cfg_.map_frame;
    if (!in.in_map && local_ < 0) local_ = k;
    if (frames_.lookup(in.frames.base_link, in.frames.world)) {
      // A static world->base_link transform would pin the robot in place.
      *error = cfg_.source + ": static transforms connect " + std::string(world.view()) + " to " +
               std::string(cfg_.base_link_frame.view()) + "; the filter estimates that transform itself";
      return false;
    }
  }
  return true;
}

bool FusionCore::configure_navsat(std::string* error) {
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    SensorConfig& c = cfg_.sensors[i];
    if (c.params.kind != est::SensorKind::kNavSatFix) continue;
    const std::string where = cfg_.source + ": sensor '" + std::string(c.name.view()) + "'";
    if (!c.antenna_frame.empty()) {
      const auto base_T_antenna = frames_.lookup(cfg_.base_link_frame.view(), c.antenna_frame.view());
      if (!base_T_antenna) {
        *error = where + ": frame '" + std::string(c.antenna_frame.view()) + "' is not connected to '" +
                 std::string(cfg_.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
                 std::string(cfg_.base_link_frame.view()) + "' and child = '" + std::string(c.antenna_frame.view()) +
                 "' (the antenna's mounting)";
        return false;
      }
      c.params.navsat.base_p_antenna = base_T_antenna->translation;
    }
    const char* why = est::validate(c.params.navsat);
    if (why[0] != '\0') {
      *error = where + ": " + why;
      return false;
    }
    models_[i] = est::SensorModel(static_cast<std::uint8_t>(i), c.params, instance_filter(cfg_, c.instance));
    if (c.heading_sensor >= 0) heading_targets_[sensor_input(cfg_, c.heading_sensor)] |= 1u << i;
    Instance& in = instances_[c.instance < num_instances_ ? c.instance : 0];
    if (in.navsat_sensor < 0) in.navsat_sensor = i;
    in.needs_fix = in.in_map;
  }
  num_navsat_ = navsat_slot_count(cfg_);
  for (int& key : navsat_message_key_) key = -1;
  if (num_navsat_ > 0) {
    describe_navsat(cfg_, navsat_layout_);
    int k = 0;
    for (int i = 0; i < cfg_.num_sensors && k < num_navsat_; ++i) {
      if (cfg_.sensors[i].params.kind != est::SensorKind::kNavSatFix) continue;
      navsat_sensor_[k++] = i;
    }
  }
  return true;
}

void FusionCore::fill_navsat(Snapshot& s) noexcept {
  if (num_navsat_ == 0) return;
  // After the devices' slots (devices/device_layout.hpp).
  const int first = devices_ != nullptr ? devices_->slot_count() : 0;
  if (s.num_devices < first + num_navsat_) s.num_devices = first + num_navsat_;
  for (int k = 0; k < num_navsat_; ++k) {
    DeviceStatus& d = s.devices[first + k];
    d.name = navsat_layout_[k].name;
    d.hardware_id = navsat_layout_[k].hardware_id;
    const est::NavsatTransform& n = models_[navsat_sensor_[k]].navsat();
    const est::NavsatStats& st = n.stats();
    set_device_values(d, kNavsatKeys,
                      {st.accepted, st.no_fix, st.invalid_position, st.invalid_covariance, st.waiting_for_heading,
                       st.jumps, st.reanchors});
    if (!n.has_transform()) {
      d.state = n.has_heading() || n.params().use_filter_yaw ? "waiting for a fix" : "waiting for a heading";
      d.level = DeviceLevel::kStale;
    } else {
      d.state = "datum set";
      d.level = n.last() == est::NavsatRejection::kNone ? DeviceLevel::kOk : DeviceLevel::kWarn;
    }
    // The text changes only with the verdict or the datum: formatted then,
    // not every tick.
    const int key = static_cast<int>(n.last()) * 2 + (n.has_transform() ? 1 : 0);
    if (key != navsat_message_key_[k]) {
      navsat_message_key_[k] = key;
      char text[96] = "";
      if (n.last() != est::NavsatRejection::kNone) {
        std::snprintf(text, sizeof text, "last fix refused: %s", est::to_string(n.last()));
      } else if (n.has_transform()) {
        std::snprintf(text, sizeof text, "datum %.7f %.7f %.2f m", n.plane().datum().latitude_deg,
                      n.plane().datum().longitude_deg, n.plane().datum().altitude_m);
      }
      set_device_message(navsat_message_[k], text);
    }
    d.message = navsat_message_[k];
  }
}

void FusionCore::fill_standstill(Snapshot& s) noexcept {
  if (num_standstill_ == 0) return;
  // After the devices' and the navsat transforms' slots.
  const int first = (devices_ != nullptr ? devices_->slot_count() : 0) + num_navsat_;
  const int count = first + num_standstill_ <= kMaxDevices ? num_standstill_ : kMaxDevices - first;
  if (count <= 0) return;  // Hardware::create refuses such a layout; a bare core just has no room
  if (s.num_devices < first + count) s.num_devices = first + count;
  for (int k = 0; k < count; ++k) {
    DeviceStatus& d = s.devices[first + k];
    d.name = standstill_layout_[k].name;
    d.hardware_id = standstill_layout_[k].hardware_id;
    const est::StandstillGyroBias& l = *standstill_[standstill_sensor_[k]];
    const auto urad = [](double v) { return static_cast<std::int64_t>(std::llround(v * 1e6)); };
    set_device_values(d, kStandstillKeys,
                      {l.stats().blocks, l.stats().dropped, l.stats().rejected,
                       static_cast<std::int64_t>(std::llround(l.learnt_s() * 1e3)), urad(l.bias().x()),
                       urad(l.bias().y()), urad(l.bias().z())});
    d.state = l.stats().blocks > 0 ? "learnt" : "no standstill yet";  // 23 characters at most
    d.level = DeviceLevel::kOk;
  }
}

void FusionCore::feed_navsat_heading(const est::SensorSample& s) noexcept {
  // navsat_transform_node's imuCallback: the IMU's orientation, its
  // mounting taken off, until the datum is fixed.
  const auto base_T_imu = frames_.lookup(instances_[0].frames.base_link, s.frame);
  if (!base_T_imu) return;
  const Eigen::Quaterniond base_orientation = s.imu.orientation * base_T_imu->rotation.conjugate();
  for (int j = 0; j < cfg_.num_sensors; ++j) {
    if ((heading_targets_[s.sensor] & (1u << j)) != 0 && !models_[j].navsat().has_transform()) {
      models_[j].set_navsat_heading(base_orientation);
    }
  }
}

void FusionCore::apply_set_pose(const SetPoseCommand& cmd) noexcept {
  // Every instance whose world frame the command's frame is tied to by
  // static transforms: a pose in odom resets the local instance, one in map
  // the global one.
  bool applied = false;
  for (int k = 0; k < num_instances_; ++k) {
    Instance& in = instances_[k];
    const auto world_T_frame = frames_.lookup(in.frames.world, cmd.frame);
    if (!world_T_frame) continue;
    geometry::RigidTransform frame_T_base;
    frame_T_base.translation = cmd.pose.position;
    frame_T_base.rotation = cmd.pose.orientation;
    const geometry::RigidTransform world_T_base = *world_T_frame * frame_T_base;
    est::StateVector x = est::StateVector::Zero();
    x.segment<3>(est::kX) = world_T_base.translation;
    x.segment<3>(est::kRoll) = geometry::rpy_from_quaternion(world_T_base.rotation);
    // Velocities and accelerations restart at zero with the initial
    // uncertainty; the pose takes the command's covariance, as
    // robot_localization's set_pose.
    est::StateMatrix p = instance_filter(cfg_, k).initial_covariance;
    p.topLeftCorner<6, 6>() = est::rotate_covariance6(cmd.pose.covariance, world_T_frame->rotation_matrix());
    p.topRightCorner<6, 9>().setZero();
    p.bottomLeftCorner<9, 6>().setZero();
    in.filter->set_pose(cmd.stamp, x, p);
    for (int i = 0; i < cfg_.num_sensors; ++i) {
      if (cfg_.sensors[i].instance == k) models_[i].reset();
    }
    applied = true;
  }
  if (applied) {
    ++set_pose_count_;
  } else {
    ++set_pose_rejected_;
  }
}

void FusionCore::fuse(const est::SensorSample& s, TimeNs now) noexcept {
  if (s.kind == est::SensorKind::kImu && s.imu.has_orientation && heading_targets_[s.sensor] != 0) {
    feed_navsat_heading(s);
  }
  if (standstill_targets_[s.sensor] != 0 &&
      (s.kind == est::SensorKind::kOdometry || s.kind == est::SensorKind::kTwist)) {
    for (std::uint32_t m = standstill_targets_[s.sensor]; m != 0; m &= m - 1) {
      standstill_[__builtin_ctz(m)]->wheels(s.stamp, s.twist.linear.norm(), s.twist.angular.z());
    }
  }
  for (std::uint32_t m = fused_by_[s.sensor]; m != 0; m &= m - 1) fuse_into(__builtin_ctz(m), s, now);
}

void FusionCore::fuse_into(int sensor, const est::SensorSample& s, TimeNs now) noexcept {
  if (standstill_[sensor] != nullptr && s.kind == est::SensorKind::kImu && s.imu.has_angular_velocity) {
    // An IMU whose residual gyro bias the wheels teach: its rates without
    // it. Copied only here: every other sample is fused as it came.
    est::SensorSample corrected = s;
    corrected.imu.angular_velocity = standstill_[sensor]->correct(s.stamp, s.imu.angular_velocity);
    fuse_sample(sensor, corrected, now);
    return;
  }
  fuse_sample(sensor, s, now);
}

void FusionCore::fuse_sample(int sensor, const est::SensorSample& s, TimeNs now) noexcept {
  SensorStats& st = stats_[sensor];
  // robot_localization ignores a message older than its topic's previous one.
  if (st.accepted + st.rejected_mahalanobis + st.rejected_stale > 0 && s.stamp < st.last_stamp_ns) {
    ++st.rejected_invalid;
    return;
  }
  if (st.last_stamp_ns > 0 && s.stamp > st.last_stamp_ns) {
    const double inst = 1e9 / static_cast<double>(s.stamp - st.last_stamp_ns);
    st.rate_hz = st.rate_hz == 0.0 ? inst : 0.9 * st.rate_hz + 0.1 * inst;
  }
  st.last_stamp_ns = s.stamp;
  last_arrival_[sensor] = now;

  Instance& in = instances_[cfg_.sensors[sensor].instance < num_instances_ ? cfg_.sensors[sensor].instance : 0];
  est::Filter& filter = *in.filter;
  est::MeasurementBatch batch;
  if (models_[sensor].convert(s, filter.state_at(s.stamp), in.frames, &batch) != est::SampleRejection::kNone) {
    ++st.rejected_invalid;
    return;
  }
  bool any_fused = false, any_rejected = false;
  for (int k = 0; k < batch.count; ++k) {
    const est::ProcessResult r = filter.process(batch.items[k]);
    lagged_replays_ += r.replayed > 0 ? 1 : 0;
    if (r.stale) {
      ++st.rejected_stale;
      any_rejected = true;
      continue;
    }
    if (r.correct.yaw_conflict) ++st.yaw_conflicts;
    switch (r.correct.outcome) {
      case est::CorrectOutcome::kFused: any_fused = true; ++fused_total_; break;
      case est::CorrectOutcome::kRejectedMahalanobis: ++st.rejected_mahalanobis; any_rejected = true; break;
      case est::CorrectOutcome::kRejectedNumeric: ++st.rejected_invalid; any_rejected = true; break;
      case est::CorrectOutcome::kNothingToFuse: break;
    }
  }
  if (any_fused || (!any_rejected && batch.count == 0)) ++st.accepted;
  if (any_fused && s.kind == est::SensorKind::kNavSatFix) ++in.fixes_fused;
}

void FusionCore::tick(TimeNs now, const LoopStats& loop) noexcept {
  SetPoseCommand cmd;
  while (input_->set_pose_ring().try_pop(cmd)) apply_set_pose(cmd);

  if (devices_ != nullptr) devices_->before_drain(now);

  // Bounded drain: at most the ring's capacity per sensor per tick.
  int n = 0;
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    SpscRing<est::SensorSample>& ring = input_->ring(i);
    const int limit = 2 * cfg_.sensors[i].params.queue_size;
    const int before = n;
    for (int k = 0; k < limit && n < staging_capacity_ && ring.try_pop(staging_[n]); ++k) ++n;
    consumed_[i] += n - before;
  }
  // Stable insertion sort by stamp: n is small and often already ordered.
  for (int i = 1; i < n; ++i) {
    if (staging_[i].stamp >= staging_[i - 1].stamp) continue;
    est::SensorSample tmp = staging_[i];
    int j = i - 1;
    while (j >= 0 && staging_[j].stamp > tmp.stamp) {
      staging_[j + 1] = staging_[j];
      --j;
    }
    staging_[j + 1] = tmp;
  }
  for (int i = 0; i < n; ++i) fuse(staging_[i], now);
  if (n == 0) {
    for (int k = 0; k < num_instances_; ++k) instances_[k].filter->predict_if_timed_out(now);
  }

  for (int i = 0; i < cfg_.num_sensors; ++i) {
    const TimeNs timeout = sec_to_ns(instance_filter(cfg_, cfg_.sensors[i].instance).sensor_timeout_s);
    SensorStats& st = stats_[i];
    const bool timed_out = last_arrival_[i] != 0 && now - last_arrival_[i] > timeout;
    if (timed_out && !st.timed_out) ++st.timeouts;
    st.timed_out = timed_out;
  }
  publish_snapshot(now, loop);
}

void FusionCore::fill_instance(int k, InstanceSnapshot& out) noexcept {
  const Instance& in = instances_[k];
  const est::Filter& f = *in.filter;
  out.stamp_ns = f.has_time() ? f.last_measurement_time() : 0;
  out.initialized = f.initialized();
  out.awaiting_fix = in.needs_fix && in.fixes_fused == 0;
  out.fixes_fused = in.fixes_fused;
  if (k > 0) {
    Eigen::Map<est::StateVector>(out.state) = f.state();
    Eigen::Map<Eigen::Matrix<double, 15, 15, Eigen::RowMajor>>(out.covariance) = f.covariance();
  }
  const bool publishable = out.initialized && !out.awaiting_fix;
  out.has_map_odom = false;
  if (publishable && in.in_map && local_ >= 0 && local_ != k && instances_[local_].filter->initialized()) {
    // The local estimate at this instance's stamp (its history has it when
    // the stamps differ; the two usually fuse the same last sample).
    const est::StateVector& local = instances_[local_].filter->state_at(out.stamp_ns);
    const est::StateVector& global = f.state();
    geometry::RigidTransform map_T_base, odom_T_base;
    map_T_base.translation = global.segment<3>(est::kX);
    map_T_base.rotation = geometry::quaternion_from_rpy(global[est::kRoll], global[est::kPitch], global[est::kYaw]);
    odom_T_base.translation = local.segment<3>(est::kX);
    odom_T_base.rotation = geometry::quaternion_from_rpy(local[est::kRoll], local[est::kPitch], local[est::kYaw]);
    const geometry::RigidTransform map_T_odom = map_T_base * odom_T_base.inverse();
    for (int a = 0; a < 3; ++a) out.map_odom_translation[a] = map_T_odom.translation[a];
    out.map_odom_rotation[0] = map_T_odom.rotation.x();
    out.map_odom_rotation[1] = map_T_odom.rotation.y();
    out.map_odom_rotation[2] = map_T_odom.rotation.z();
    out.map_odom_rotation[3] = map_T_odom.rotation.w();
    out.has_map_odom = true;
  }
  out.has_filtered_fix = false;
  if (publishable && in.navsat_sensor >= 0 && models_[in.navsat_sensor].navsat().has_transform()) {
    const est::StateVector& x = f.state();
    const est::StateMatrix p = f.covariance();
    const est::NavSatFixSample fix =
        models_[in.navsat_sensor].navsat().filtered_fix(x.segment<3>(est::kX), p.topLeftCorner<3, 3>());
    out.latitude_deg = fix.position.latitude_deg;
    out.longitude_deg = fix.position.longitude_deg;
    out.altitude_m = fix.position.altitude_m;
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(out.fix_covariance) = fix.covariance;
    out.has_filtered_fix = true;
  }
}

void FusionCore::publish_snapshot(TimeNs now, const LoopStats& loop) noexcept {
  Snapshot& s = scratch_;
  const est::Filter& filter = *instances_[0].filter;
  s.tick_time_ns = now;
  s.stamp_ns = filter.has_time() ? filter.last_measurement_time() : now;
  s.seq = ++seq_;
  s.initialized = filter.initialized();
  Eigen::Map<est::StateVector>(s.state) = filter.state();
  Eigen::Map<Eigen::Matrix<double, 15, 15, Eigen::RowMajor>>(s.covariance) = filter.covariance();
  s.num_instances = num_instances_;
  for (int k = 0; k < num_instances_; ++k) fill_instance(k, s.instances[k]);
  s.instances[0].stamp_ns = s.stamp_ns;
  s.awaiting_fix = s.instances[0].awaiting_fix;
  s.loop = loop;
  s.loop.measurements_fused = fused_total_;
  s.loop.lagged_replays = lagged_replays_;
  s.unknown_channel_messages = input_->unknown_channel_messages();
  s.set_pose_count = set_pose_count_;
  s.set_pose_rejected = set_pose_rejected_ + input_->set_pose_decode_errors();
  s.set_pose_ignored = input_->set_pose_ignored();
  s.num_sensors = cfg_.num_sensors;
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    SensorStats st = stats_[i];
    // A shared input's counters are its first sensor's.
    const InputCounters& c = input_->counters(sensor_input(cfg_, i));
    st.received = c.received.load(std::memory_order_relaxed);
    st.decode_errors = c.decode_errors.load(std::memory_order_relaxed);
    st.rejected_overflow = c.overflow.load(std::memory_order_relaxed);
    st.rejected_rate = c.rate_limited.load(std::memory_order_relaxed);
    st.rejected_oversize = c.oversize.load(std::memory_order_relaxed);
    st.rejected_invalid += c.ahead.load(std::memory_order_relaxed);
    s.sensors[i] = st;
  }
  s.num_devices = 0;
  s.wheel_odometry.valid = false;
  if (devices_ != nullptr) devices_->fill_snapshot(s);
  fill_navsat(s);
  fill_standstill(s);
  snapshot_.store(s);
}

}  // namespace rtfuse
