#include "runtime/devices/mapper/mapper_device.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotation.hpp"
#include "transport/occupancy_grid_message.hpp"

namespace rtfuse {

// keyframes: pairs taken as keyframe candidates; dropped: of those, lost to
// a full queue (the mapper fell behind); pool_permille: bricks in use of
// the pool; disparity_us / insert_us: the last keyframe's two halves;
// max_us: the longest keyframe so far; rate_milli: keyframes mapped per
// second of capture time, x1000; digest: mapping/map_digest.hpp's, as a
// signed 64-bit number.
const char* const kMapperKeys[17] = {"keyframes", "inserted",   "dropped",       "still",        "no_pose",
                                     "bad_pose",  "points",     "known",         "occupied",     "pool_permille",
                                     "dropped_updates", "disparity_us", "insert_us", "max_us",     "rate_milli",
                                     "grids",     "digest"};

namespace {

// How long the mapper's thread sleeps when nothing is due: a keyframe
// waits pose_delay for the loop anyway, so a few milliseconds cost nothing.
constexpr TimeNs kIdleSleepNs = 5'000'000;
// Loop ticks waiting for the mapper: seconds of a 1 kHz loop, so a keyframe
// that takes long to map loses none of the poses after it.
constexpr int kPoseRing = 8192;
// Poses kept: the delay plus the queue's keyframes at any loop rate here.
constexpr int kPoseHistory = 8192;

TimeNs seconds_ns(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

mapping::KeyframeMapperParams mapper_params(const MappingSection& m) {
  mapping::KeyframeMapperParams p;
  p.disparity.disparities = m.disparities;
  p.disparity.downscale = m.half_resolution ? 2 : 1;
  p.texture.min_mean_gradient = m.min_texture;
  p.occupancy.resolution = m.resolution_m;
  p.occupancy.prob_hit = m.prob_hit;
  p.occupancy.prob_miss = m.prob_miss;
  p.occupancy.clamp_min = m.clamp_min;
  p.occupancy.clamp_max = m.clamp_max;
  p.occupancy.occupancy_threshold = m.occupancy_threshold;
  p.max_range_m = m.max_range_m;
  p.pool_bytes = static_cast<std::size_t>(m.memory_mb) << 20;
  return p;
}

}  // namespace

MapperDevice::MapperDevice(FrameSource& camera, int slot)
    : camera_(camera), slot_(slot), poses_(kPoseRing), history_(kPoseHistory) {}

MapperDevice::~MapperDevice() {
  // Pairs still queued go back to the camera's pool, which outlives us.
  FramePool::Handle h;
  while (queue_.try_pop(h)) camera_.pool().release(h);
}

std::unique_ptr<MapperDevice> MapperDevice::create(FrameSource& camera, FusionCore& core, int slot,
                                                   std::string* error) {
  const RuntimeConfig& cfg = core.config();
  const MappingSection& m = cfg.hardware.mapping;
  const CameraSection& c = cfg.hardware.camera;
  const auto mount = core.frames().lookup(cfg.base_link_frame.view(), c.frame.view());
  if (!mount) {
    *error = "[mapping]: camera.frame '" + std::string(c.frame.view()) + "' is not connected to '" +
             std::string(cfg.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
             std::string(cfg.base_link_frame.view()) + "' and child = '" + std::string(c.frame.view()) + "'";
    return nullptr;
  }
  const drivers::StereoRectification& r = camera.rectified();
  if (std::abs(r.fx - r.fy) > 1e-6 * std::abs(r.fx)) {
    *error = "[mapping]: the rectified eyes have fx " + std::to_string(r.fx) + " and fy " + std::to_string(r.fy) +
             "; depth from disparity needs square pixels";
    return nullptr;
  }
  std::unique_ptr<MapperDevice> d(new MapperDevice(camera, slot));
  d->config_ = m;
  d->base_T_camera_ = *mount;
  d->interval_ns_ = seconds_ns(m.keyframe_interval_s);
  d->pose_delay_ns_ = seconds_ns(m.pose_delay_s);
  d->grid_period_ns_ = m.grid_rate_hz > 0.0 ? seconds_ns(1.0 / m.grid_rate_hz) : 0;
  const vision::StereoCameraModel model{r.fx, r.cx, r.cy, r.baseline_m};
  d->mapper_ = mapping::KeyframeMapper::create(r.width, r.height, model, mapper_params(m), error);
  if (!d->mapper_) {
    *error = "[mapping]: " + *error;
    return nullptr;
  }
  // Resident now: the daemon's memory stays flat while the map grows.
  d->mapper_->map().prefault();
  const int side = static_cast<int>(std::lround(m.grid_size_m / m.resolution_m));
  d->spec_ = mapping::grid_around(d->mapper_->map().grid(), 0.0, 0.0, side, side, m.grid_min_z_m, m.grid_max_z_m);
  const std::size_t cells = d->spec_.cells();
  for (int i = 0; i < 3; ++i) d->grids_.buffer(i).cells.reset(new std::int8_t[cells]);
  d->final_cells_.reset(new std::int8_t[cells]);
  std::fill(d->final_cells_.get(), d->final_cells_.get() + cells, mapping::kCellUnknown);
  d->digest_.reset(new mapping::MapDigest(d->mapper_->map()));
  d->grid_.reset(new mapping::ProjectedGrid(d->mapper_->map(), d->spec_));
  d->trajectory_.reset(new KeyframePlace[kTrajectoryCapacity]);
  if (d->grid_period_ns_ > 0) {
    d->encoder_ = transport::OccupancyGridEncoder::create(static_cast<int>(cells),
                                                          std::string(cfg.world_frame.view()), 0, error);
    if (!d->encoder_) {
      *error = "[mapping]: " + *error;
      return nullptr;
    }
  }
  d->stats_.bricks_capacity = d->mapper_->map().store().capacity().bricks;
  d->health_.store(d->stats_);
  return d;
}

void MapperDevice::on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept {
  const FramePool::Frame f = pool.frame(newest);
  if (any_candidate_ && f.stamp < next_candidate_) return;
  // Due times step by the interval, so 0.2 s at 30 fps gives 5 keyframes a
  // second, not one every seventh frame; after a gap they start again from
  // this pair. They follow from the pairs' stamps alone, mapped or not.
  next_candidate_ = any_candidate_ ? next_candidate_ + interval_ns_ : f.stamp + interval_ns_;
  if (next_candidate_ <= f.stamp) next_candidate_ = f.stamp + interval_ns_;
  any_candidate_ = true;
  candidates_.fetch_add(1, std::memory_order_relaxed);
  FramePool::Handle mine = pool.retain(newest);
  if (!queue_.try_push(mine)) {
    pool.release(mine);
    dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void MapperDevice::fill_snapshot(Snapshot& s) noexcept {
  LoopPose p;
  p.tick = s.tick_time_ns;
  p.stamp = s.stamp_ns;
  p.initialized = s.initialized;
  p.x = s.state[0];
  p.y = s.state[1];
  p.z = s.state[2];
  p.roll = s.state[3];
  p.pitch = s.state[4];
  p.yaw = s.state[5];
  if (!poses_.try_push(p)) poses_lost_.fetch_add(1, std::memory_order_relaxed);
  if (slot_ < 0) return;
  MapperStats v;
  health_.load(v);
  const std::int64_t permille = v.bricks_capacity > 0 ? v.bricks_used * 1000 / v.bricks_capacity : 0;
  const TimeNs span = v.last_stamp - v.first_stamp;
  // In floating point: (inserted - 1) * 1e12 would overflow an int64 after
  // three weeks of mapping at 5 a second.
  const std::int64_t rate_milli =
      v.inserted > 1 && span > 0
          ? std::llround(static_cast<double>(v.inserted - 1) * 1e12 / static_cast<double>(span))
          : 0;
  DeviceStatus& d = s.devices[slot_];
  set_device_values(d, kMapperKeys,
                    {candidates_.load(std::memory_order_relaxed), v.inserted, dropped_.load(std::memory_order_relaxed),
                     v.still, v.no_pose, v.bad_pose, v.points, v.known, v.occupied, permille, v.dropped_updates,
                     v.disparity_ns / 1000, v.insert_ns / 1000, v.max_keyframe_ns / 1000, rate_milli, v.grids,
                     static_cast<std::int64_t>(v.digest)});
  if (v.dropped_updates > 0) {
    d.level = DeviceLevel::kError;
    d.state = "pool full";
    set_device_message(d.message, "the map's pool is full and it stopped growing: raise [mapping] memory_mb");
  } else if (v.inserted == 0) {
    d.level = DeviceLevel::kStale;
    d.state = "waiting";
  } else {
    d.level = DeviceLevel::kOk;
    d.state = "mapping";
  }
}

void MapperDevice::take_poses() noexcept {
  LoopPose p;
  while (poses_.try_pop(p)) {
    newest_tick_ = p.tick;
    if (!p.initialized) continue;
    geometry::RigidTransform pose;
    pose.translation = Eigen::Vector3d(p.x, p.y, p.z);
    pose.rotation = geometry::quaternion_from_rpy(p.roll, p.pitch, p.yaw);
    history_.add(p.stamp, pose, p.tick);
  }
}

bool MapperDevice::map_due_keyframe() noexcept {
  const FramePool::Handle* h = queue_.peek();
  if (h == nullptr) return false;
  const FramePool::Frame f = camera_.pool().frame(*h);
  const TimeNs as_of = f.stamp + pose_delay_ns_;
  if (newest_tick_ < as_of) return false;
  geometry::RigidTransform world_T_base;
  const geometry::PoseLookup found = history_.at(f.stamp, &world_T_base, as_of);
  if (found != geometry::PoseLookup::kOk) {
    ++stats_.no_pose;
  } else if (!world_T_base.translation.allFinite() || !world_T_base.rotation.coeffs().allFinite()) {
    ++stats_.bad_pose;
  } else {
    map_keyframe(f, world_T_base);
  }
  FramePool::Handle done = *h;
  queue_.pop();
  camera_.pool().release(done);
  return true;
}

void MapperDevice::map_keyframe(const FramePool::Frame& f, const geometry::RigidTransform& world_T_base) noexcept {
  if (have_last_ && (config_.keyframe_distance_m > 0.0 || config_.keyframe_angle_rad > 0.0)) {
    const double moved = (world_T_base.translation - last_mapped_.translation).norm();
    const double turned = last_mapped_.rotation.angularDistance(world_T_base.rotation);
    if (moved < config_.keyframe_distance_m && turned < config_.keyframe_angle_rad) {
      ++stats_.still;
      // Nothing new to map, but the map is as current as this keyframe.
      for (int i = 0; i < num_grid_consumers_; ++i) grid_consumers_[i]->on_map_current(f.stamp);
      return;
    }
  }
  const geometry::RigidTransform world_T_camera = world_T_base * base_T_camera_;
  const TimeNs t0 = monotonic_now_ns();
  const mapping::KeyframePoints pts = mapper_->points_of({f.left, f.width, f.height, f.stride},
                                                          {f.right, f.width, f.height, f.stride}, world_T_camera);
  const TimeNs t1 = monotonic_now_ns();
  if (!pts.ok) {
    ++stats_.refused;
    return;
  }
  mapper_->insert();
  digest_->note_scan(mapper_->map());
  grid_->note_scan(mapper_->map());
  const TimeNs t2 = monotonic_now_ns();
  have_last_ = true;
  last_mapped_ = world_T_base;
  const mapping::OccupancyMap& map = mapper_->map();
  MapperStats& s = stats_;
  if (s.inserted == 0) s.first_stamp = f.stamp;
  ++s.inserted;
  s.last_stamp = f.stamp;
  s.points = pts.counts.points;
  s.known = static_cast<std::int64_t>(map.known_voxels());
  s.occupied = static_cast<std::int64_t>(map.occupied_voxels());
  s.bricks_used = map.store().bricks_used();
  s.dropped_updates = static_cast<std::int64_t>(map.dropped_updates());
  s.disparity_ns = t1 - t0;
  s.insert_ns = t2 - t1;
  if (t2 - t0 > s.max_keyframe_ns) s.max_keyframe_ns = t2 - t0;
  if (trajectory_size_ < kTrajectoryCapacity) {
    trajectory_[trajectory_size_++] = {f.stamp, world_T_camera.translation.x(), world_T_camera.translation.y()};
  }
  if (grid_period_ns_ > 0 && f.stamp >= next_grid_) {
    // Due times a period apart, like the keyframes', so 1 Hz is 1 Hz.
    next_grid_ = s.grids == 0 ? f.stamp + grid_period_ns_ : next_grid_ + grid_period_ns_;
    if (next_grid_ <= f.stamp) next_grid_ = f.stamp + grid_period_ns_;
    s.digest = digest_->refresh(map);
    Grid& g = grids_.write_buffer();
    const std::int8_t* cells = grid_->refresh(map);
    std::copy(cells, cells + spec_.cells(), g.cells.get());
    g.stamp = f.stamp;
    grids_.publish();
    ++s.grids;
    for (int i = 0; i < num_grid_consumers_; ++i) grid_consumers_[i]->on_grid(cells, f.stamp);
  }
  for (int i = 0; i < num_grid_consumers_; ++i) grid_consumers_[i]->on_map_current(f.stamp);
}

bool MapperDevice::attach(GridConsumer& consumer, std::string* error) {
  if (grid_period_ns_ <= 0) {
    *error = "[mapping] makes no grid (grid_rate = 0): nothing to plan on";
    return false;
  }
  if (num_grid_consumers_ == kMaxGridConsumers) {
    *error = "the mapper's grid has " + std::to_string(kMaxGridConsumers) + " consumers already";
    return false;
  }
  grid_consumers_[num_grid_consumers_++] = &consumer;
  return true;
}

GridLayout MapperDevice::grid_layout() const noexcept {
  GridLayout g;
  g.width = spec_.width;
  g.height = spec_.height;
  g.resolution_m = config_.resolution_m;
  g.origin_x = mapping::grid_origin_x(mapper_->map().grid(), spec_);
  g.origin_y = mapping::grid_origin_y(mapper_->map().grid(), spec_);
  return g;
}

void MapperDevice::step(TimeNs timeout_ns) noexcept {
  take_poses();
  bool mapped = false;
  while (map_due_keyframe()) mapped = true;
  if (mapped) health_.store(stats_);
  if (!mapped && timeout_ns > 0) sleep_until(monotonic_now_ns() + std::min(timeout_ns, kIdleSleepNs));
}

void MapperDevice::finish() noexcept {
  take_poses();
  while (map_due_keyframe()) {
  }
  const std::int8_t* cells = grid_->refresh(mapper_->map());
  std::copy(cells, cells + spec_.cells(), final_cells_.get());
  stats_.digest = digest_->refresh(mapper_->map());
  health_.store(stats_);
}

MapperStats MapperDevice::stats() const noexcept {
  MapperStats v;
  health_.load(v);
  return v;
}

void MapperDevice::publish_due(TimeNs now, transport::MessageSink& sink) noexcept {
  if (!encoder_) return;
  const Grid* g = grids_.take_newest();
  if (g == nullptr) return;
  transport::OccupancyGridLayout layout;
  layout.width = spec_.width;
  layout.height = spec_.height;
  layout.resolution = config_.resolution_m;
  layout.origin_x = mapping::grid_origin_x(mapper_->map().grid(), spec_);
  layout.origin_y = mapping::grid_origin_y(mapper_->map().grid(), spec_);
  const transport::EncodedMessage msg = encoder_->encode(layout, g->cells.get(), g->stamp);
  if (msg.ok()) sink.publish(config_.grid_channel.c_str(), msg.data, msg.size, now);
}

}  // namespace rtfuse
