#include "runtime/fusion_core.hpp"

#include <cmath>
#include <cstdio>

#include "geometry/rotation.hpp"

namespace rtfuse {

std::unique_ptr<FusionCore> FusionCore::create(const RuntimeConfig& cfg, std::string* error) {
  std::unique_ptr<FusionCore> core(new FusionCore(cfg));
  if (!core->build_frames(error)) return nullptr;
  if (!core->configure_navsat(error)) return nullptr;
  core->input_ = std::make_unique<InputRouter>(core->cfg_, core->frames_);
  return core;
}

FusionCore::FusionCore(const RuntimeConfig& cfg) : cfg_(cfg) {
  filter_ = std::make_unique<est::Filter>(cfg_.filter);
  int absolute_yaw_sources = 0;
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    models_[i] = est::SensorModel(static_cast<std::uint8_t>(i), cfg_.sensors[i].params, cfg_.filter);
    if (models_[i].fuses_absolute_yaw()) ++absolute_yaw_sources;
    staging_capacity_ += 2 * cfg_.sensors[i].params.queue_size;
  }
  // One absolute yaw source cannot conflict with anything; two can, and then
  // robot_localization would pull the estimate back and forth between them.
  if (absolute_yaw_sources >= 2) {
    for (int i = 0; i < cfg_.num_sensors; ++i) models_[i].set_yaw_gate(cfg_.filter.yaw_conflict_gate_sigma);
  }
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
  fusion_frames_.tree = &frames_;
  fusion_frames_.world = frames_.find(cfg_.world_frame.view());
  fusion_frames_.base_link = frames_.find(cfg_.base_link_frame.view());
  if (frames_.lookup(fusion_frames_.base_link, fusion_frames_.world)) {
    // A static world->base_link transform would pin the robot in place.
    *error = cfg_.source + ": static transforms connect " + std::string(cfg_.world_frame.view()) + " to " +
             std::string(cfg_.base_link_frame.view()) + "; the filter estimates that transform itself";
    return false;
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
    models_[i] = est::SensorModel(static_cast<std::uint8_t>(i), c.params, cfg_.filter);
    if (c.heading_sensor >= 0) heading_targets_[c.heading_sensor] |= 1u << i;
  }
  slots_ = device_slots(cfg_);
  for (int& key : navsat_message_key_) key = -1;
  if (slots_.num_navsat > 0) {
    const auto layout = std::make_unique<DeviceStatus[]>(kMaxDevices);
    describe_devices(cfg_, layout.get(), kMaxDevices);
    int k = 0;
    for (int i = 0; i < cfg_.num_sensors && k < slots_.num_navsat; ++i) {
      if (cfg_.sensors[i].params.kind != est::SensorKind::kNavSatFix) continue;
      navsat_layout_[k] = layout[slots_.first_navsat + k];
      navsat_sensor_[k++] = i;
    }
  }
  return true;
}

void FusionCore::fill_navsat(Snapshot& s) noexcept {
  if (slots_.num_navsat == 0) return;
  if (s.num_devices < slots_.count) s.num_devices = slots_.count;
  for (int k = 0; k < slots_.num_navsat; ++k) {
    DeviceStatus& d = s.devices[slots_.first_navsat + k];
    d.name = navsat_layout_[k].name;
    d.hardware_id = navsat_layout_[k].hardware_id;
    const est::NavsatTransform& n = models_[navsat_sensor_[k]].navsat();
    const est::NavsatStats& st = n.stats();
    set_device_values(d, kNavsatKeys, kNavsatKeyCount,
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

void FusionCore::feed_navsat_heading(const est::SensorSample& s) noexcept {
  // navsat_transform_node's imuCallback: the IMU's orientation, its
  // mounting taken off, until the datum is fixed.
  const auto base_T_imu = frames_.lookup(fusion_frames_.base_link, s.frame);
  if (!base_T_imu) return;
  const Eigen::Quaterniond base_orientation = s.imu.orientation * base_T_imu->rotation.conjugate();
  for (int j = 0; j < cfg_.num_sensors; ++j) {
    if ((heading_targets_[s.sensor] & (1u << j)) != 0 && !models_[j].navsat().has_transform()) {
      models_[j].set_navsat_heading(base_orientation);
    }
  }
}

void FusionCore::apply_set_pose(const SetPoseCommand& cmd) noexcept {
  const auto world_T_frame = frames_.lookup(fusion_frames_.world, cmd.frame);
  if (!world_T_frame) {
    ++set_pose_rejected_;
    return;
  }
  geometry::RigidTransform frame_T_base;
  frame_T_base.translation = cmd.pose.position;
  frame_T_base.rotation = cmd.pose.orientation;
  const geometry::RigidTransform world_T_base = *world_T_frame * frame_T_base;
  est::StateVector x = est::StateVector::Zero();
  x.segment<3>(est::kX) = world_T_base.translation;
  x.segment<3>(est::kRoll) = geometry::rpy_from_quaternion(world_T_base.rotation);
  // Velocities and accelerations restart at zero with the initial uncertainty;
  // the pose takes the command's covariance, as robot_localization's set_pose.
  est::StateMatrix p = cfg_.filter.initial_covariance;
  p.topLeftCorner<6, 6>() = est::rotate_covariance6(cmd.pose.covariance, world_T_frame->rotation_matrix());
  p.topRightCorner<6, 9>().setZero();
  p.bottomLeftCorner<9, 6>().setZero();
  filter_->set_pose(cmd.stamp, x, p);
  for (int i = 0; i < cfg_.num_sensors; ++i) models_[i].reset();
  ++set_pose_count_;
}

void FusionCore::fuse(const est::SensorSample& s, TimeNs now) noexcept {
  SensorStats& st = stats_[s.sensor];
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
  last_arrival_[s.sensor] = now;
  if (s.kind == est::SensorKind::kImu && s.imu.has_orientation && heading_targets_[s.sensor] != 0) {
    feed_navsat_heading(s);
  }

  est::MeasurementBatch batch;
  if (models_[s.sensor].convert(s, filter_->state_at(s.stamp), fusion_frames_, &batch) != est::SampleRejection::kNone) {
    ++st.rejected_invalid;
    return;
  }
  bool any_fused = false, any_rejected = false;
  for (int k = 0; k < batch.count; ++k) {
    const est::ProcessResult r = filter_->process(batch.items[k]);
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
  if (n == 0) filter_->predict_if_timed_out(now);

  const TimeNs timeout = sec_to_ns(cfg_.filter.sensor_timeout_s);
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    SensorStats& st = stats_[i];
    const bool timed_out = last_arrival_[i] != 0 && now - last_arrival_[i] > timeout;
    if (timed_out && !st.timed_out) ++st.timeouts;
    st.timed_out = timed_out;
  }
  publish_snapshot(now, loop);
}

void FusionCore::publish_snapshot(TimeNs now, const LoopStats& loop) noexcept {
  Snapshot& s = scratch_;
  s.tick_time_ns = now;
  s.stamp_ns = filter_->has_time() ? filter_->last_measurement_time() : now;
  s.seq = ++seq_;
  s.initialized = filter_->initialized();
  Eigen::Map<est::StateVector>(s.state) = filter_->state();
  Eigen::Map<Eigen::Matrix<double, 15, 15, Eigen::RowMajor>>(s.covariance) = filter_->covariance();
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
    const InputCounters& c = input_->counters(i);
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
  snapshot_.store(s);
}

}  // namespace rtfuse
