#pragma once
// The occupancy mapper as the camera's second frame consumer, on a thread
// of its own (device_descriptor.hpp, DeviceScheduling::kWorker):
//
//   camera thread  on_pair(): the first pair at or after each due time
//                  (keyframe_interval apart) is kept (a retained handle) in a queue of
//                  two; a full queue drops it, counted: the mapper fell
//                  behind, capture never waits.
//   loop thread    fill_snapshot(): the tick's estimate (world -> base_link
//                  and its stamp) into an SPSC ring; the mapper's health
//                  out of a SeqLatch into its diagnostics slot.
//   mapper thread  step(): the loop's poses into a PoseHistory; each queued
//                  keyframe, once the loop is pose_delay past its stamp,
//                  placed with the pose at its stamp as the loop had it
//                  then, its disparity turned into points and inserted
//                  (mapping/keyframe_mapper.hpp); at grid_rate the map's
//                  digest and 2-D grid brought up to date from the bricks
//                  the keyframes since wrote (their work, however large
//                  the map), the grid into a triple buffer.
//   publisher      publish_due(): the newest grid as occupancy_grid_t.
//
// What it maps depends on the pairs lent and the loop's estimates only,
// never on when its thread ran: a keyframe's pose is looked up "as of" the
// tick pose_delay after its stamp, whenever the lookup happens. So a
// replay or a lockstep drive, which step it after every tick (a replay
// also after every camera step: its pairs can come in bursts), builds the
// same map, bit for bit, as the live thread did, unless the live queue
// overflowed (counted in `dropped`).
//
// Allocates in create() only.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "core/seq_cell.hpp"
#include "core/spsc_ring.hpp"
#include "core/triple_buffer.hpp"
#include "geometry/pose_history.hpp"
#include "geometry/rigid_transform.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/keyframe_mapper.hpp"
#include "mapping/map_digest.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/frame_consumer.hpp"
#include "runtime/devices/grid_consumer.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

namespace transport {
class OccupancyGridEncoder;
}

extern const char* const kMapperKeys[17];

// The mapper's health, written by its thread.
struct MapperStats {
  std::int64_t inserted = 0;     // keyframes in the map
  std::int64_t still = 0;        // not mapped: the robot had not moved enough
  std::int64_t no_pose = 0;      // no estimate at the stamp pose_delay after it (filter not running)
  std::int64_t bad_pose = 0;     // not finite
  std::int64_t refused = 0;      // the matcher refused the pair
  std::int64_t points = 0;       // of the last keyframe
  std::int64_t known = 0;
  std::int64_t occupied = 0;
  std::int64_t bricks_used = 0;
  std::int64_t bricks_capacity = 0;
  std::int64_t dropped_updates = 0;  // voxel updates lost to a full pool
  std::int64_t grids = 0;
  TimeNs disparity_ns = 0;       // the last keyframe's disparity and points
  TimeNs insert_ns = 0;          // its insertion
  TimeNs max_keyframe_ns = 0;
  std::uint64_t digest = 0;      // mapping/map_digest.hpp, at the last grid and at finish()
  TimeNs first_stamp = 0;        // of the keyframes mapped
  TimeNs last_stamp = 0;
};

// One keyframe's place, for the trajectory drawn over the map.
struct KeyframePlace {
  TimeNs stamp = 0;
  double x = 0.0, y = 0.0;
};

namespace mapper_detail {
// Ring and buffer slots (outside the class: a nested type with member
// initialisers is not default-constructible, for SpscRing's checks, until
// the class ends).
// The loop's estimate at one tick.
struct LoopPose {
  TimeNs tick = 0;
  TimeNs stamp = 0;
  bool initialized = false;
  double x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;
};
struct Grid {
  std::unique_ptr<std::int8_t[]> cells;
  TimeNs stamp = 0;
};
}  // namespace mapper_detail

class MapperDevice final : public Device, public FrameConsumer, public GridSource {
 public:
  static constexpr int kQueueFrames = 2;
  static constexpr int kTrajectoryCapacity = 1 << 15;

  // On the pairs of `camera`; the configuration is the core's ([mapping],
  // camera.frame's mount). Null with *error when the rectified camera, the
  // mount or the map's parameters cannot work.
  static std::unique_ptr<MapperDevice> create(FrameSource& camera, FusionCore& core, int slot, std::string* error);
  ~MapperDevice() override;

  // Device.
  // timeout_ns > 0 (its own thread): maps what is due, or sleeps a few
  // milliseconds when nothing is; 0 (lockstep): maps what is due, never waits.
  void step(TimeNs timeout_ns) noexcept override;
  void fill_snapshot(Snapshot& s) noexcept override;
  void publish_due(TimeNs now, transport::MessageSink& sink) noexcept override;
  FrameConsumer* frame_consumer() noexcept override { return this; }
  GridSource* grid_source() noexcept override { return grid_period_ns_ > 0 ? this : nullptr; }
  // GridSource: its consumers are called on the mapper's thread.
  bool attach(GridConsumer& consumer, std::string* error) override;
  GridLayout grid_layout() const noexcept override;

  // After every thread stopped: what is due by the last tick, then the
  // final grid. Live, replay and a lockstep drive end on the same map.
  void finish() noexcept override;

  // FrameConsumer.
  const char* name() const noexcept override { return "mapper"; }
  int frames_held() const noexcept override { return kQueueFrames; }
  void on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept override;

  // After finish() (or between lockstep steps): the map and what it was
  // made of, for the files a tool writes.
  const mapping::OccupancyMap& map() const noexcept { return mapper_->map(); }
  const mapping::GridSpec& grid_spec() const noexcept { return spec_; }
  const std::int8_t* grid_cells() const noexcept { return final_cells_.get(); }
  const KeyframePlace* trajectory() const noexcept { return trajectory_.get(); }
  int trajectory_size() const noexcept { return trajectory_size_; }
  MapperStats stats() const noexcept;
  std::int64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  const MappingSection& config() const noexcept { return config_; }

 private:
  using LoopPose = mapper_detail::LoopPose;
  using Grid = mapper_detail::Grid;

  MapperDevice(FrameSource& camera, int slot);
  void take_poses() noexcept;
  // The first queued keyframe, if the loop is pose_delay past it: mapped,
  // or dropped with its reason. False when none is due.
  bool map_due_keyframe() noexcept;
  void map_keyframe(const FramePool::Frame& f, const geometry::RigidTransform& world_T_base) noexcept;

  FrameSource& camera_;
  int slot_ = -1;
  MappingSection config_;
  TimeNs interval_ns_ = 0;
  TimeNs pose_delay_ns_ = 0;
  TimeNs grid_period_ns_ = 0;
  geometry::RigidTransform base_T_camera_;

  // Camera thread.
  TimeNs next_candidate_ = 0;
  bool any_candidate_ = false;
  std::atomic<std::int64_t> candidates_{0};
  std::atomic<std::int64_t> dropped_{0};
  SpscRing<FramePool::Handle> queue_{kQueueFrames};

  // Loop thread -> mapper thread.
  SpscRing<LoopPose> poses_;
  std::atomic<std::int64_t> poses_lost_{0};

  // Mapper thread.
  geometry::PoseHistory history_;
  TimeNs newest_tick_ = 0;
  std::unique_ptr<mapping::KeyframeMapper> mapper_;
  mapping::GridSpec spec_;
  TimeNs next_grid_ = 0;
  bool have_last_ = false;
  geometry::RigidTransform last_mapped_;
  std::unique_ptr<KeyframePlace[]> trajectory_;
  int trajectory_size_ = 0;
  std::unique_ptr<mapping::MapDigest> digest_;  // kept up to date from the keyframes' bricks
  std::unique_ptr<mapping::ProjectedGrid> grid_;  // likewise
  std::unique_ptr<std::int8_t[]> final_cells_;
  MapperStats stats_;
  SeqLatch<MapperStats> health_;
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);

  static constexpr int kMaxGridConsumers = 2;
  GridConsumer* grid_consumers_[kMaxGridConsumers] = {};
  int num_grid_consumers_ = 0;

  // Mapper thread -> publisher thread.
  TripleBuffer<Grid> grids_;
  std::unique_ptr<transport::OccupancyGridEncoder> encoder_;  // publisher thread
};

}  // namespace rtfuse
