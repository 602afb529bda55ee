#pragma once
// The loop's work for one tick, free of threads and clocks so the daemon and
// the replay run exactly the same code: drain the rings (bounded), order by
// stamp, preprocess and fuse, then publish a snapshot through the seqlock.
#include <memory>

#include "core/seq_cell.hpp"
#include "estimation/filter.hpp"
#include "estimation/sensor_model.hpp"
#include "estimation/standstill_gyro_bias.hpp"
#include "geometry/frame_tree.hpp"
#include "runtime/config/config.hpp"
#include "runtime/fusion/input_router.hpp"
#include "runtime/fusion/snapshot.hpp"

namespace rtfuse {

// Work the loop does for the devices it drives, inside the tick: poll the
// polled ones (their samples go into the sensors' rings before the drain)
// and report device health (and raw wheel odometry) into the snapshot's
// first slot_count() device slots. devices/hardware.cpp.
class TickDevices {
 public:
  virtual ~TickDevices() = default;
  virtual void before_drain(TimeNs now) noexcept = 0;
  virtual void fill_snapshot(Snapshot& s) noexcept = 0;
  virtual int slot_count() const noexcept = 0;
};

class FusionCore {
 public:
  // Builds the frame tree from the static transforms; *error on a bad tree.
  static std::unique_ptr<FusionCore> create(const RuntimeConfig& cfg, std::string* error);

  InputRouter& input() { return *input_; }
  const geometry::FrameTree& frames() const { return frames_; }
  const RuntimeConfig& config() const { return cfg_; }

  // One loop iteration at loop time `now`. Never allocates, locks or blocks.
  void tick(TimeNs now, const LoopStats& loop) noexcept;
  const SeqLock<Snapshot>& snapshot() const { return snapshot_; }
  // The snapshot of the last tick, for the loop thread itself (no seqlock).
  const Snapshot& last_snapshot() const { return scratch_; }
  // The first instance's filter, and instance k's.
  const est::Filter& filter() const { return *instances_[0].filter; }
  const est::Filter& filter(int k) const { return *instances_[k].filter; }
  int num_instances() const { return num_instances_; }

  // Not owned; set before the loop starts.
  void set_devices(TickDevices* devices) { devices_ = devices; }
  // Samples the loop has taken from each sensor's ring since start, up to
  // and including the last tick: what a recording needs to replay the same
  // samples into the same ticks.
  const std::int64_t* consumed() const { return consumed_; }

 private:
  explicit FusionCore(const RuntimeConfig& cfg);
  bool build_frames(std::string* error);
  void build_instances();
  // navsat sensors: lever arms from the frame tree, heading IMUs.
  bool configure_navsat(std::string* error);
  void feed_navsat_heading(const est::SensorSample& s) noexcept;
  void apply_set_pose(const SetPoseCommand& cmd) noexcept;
  // One sample of an input, into every instance that fuses it.
  void fuse(const est::SensorSample& s, TimeNs now) noexcept;
  void fuse_into(int sensor, const est::SensorSample& s, TimeNs now) noexcept;
  // fuse_into's work, once an IMU's learnt gyro bias is off its rates.
  void fuse_sample(int sensor, const est::SensorSample& s, TimeNs now) noexcept;
  void publish_snapshot(TimeNs now, const LoopStats& loop) noexcept;
  void fill_instance(int k, InstanceSnapshot& out) noexcept;
  // The navsat transforms' slots of the diagnostics.
  void fill_navsat(Snapshot& s) noexcept;
  // The gyro bias learners' slots, after the navsat transforms'.
  void fill_standstill(Snapshot& s) noexcept;

  // A filter instance: its EKF, the frames it fuses in, and whether it is
  // anchored to the map yet.
  struct Instance {
    std::unique_ptr<est::Filter> filter;
    est::FusionFrames frames;
    bool in_map = false;       // world frame = map_frame
    bool needs_fix = false;    // in map with a navsat sensor: publishes after its first fix
    std::int64_t fixes_fused = 0;
    int navsat_sensor = -1;    // its first navsat sensor: the filtered fix
  };

  RuntimeConfig cfg_;
  geometry::FrameTree frames_;
  Instance instances_[kMaxInstances];
  int num_instances_ = 1;
  int local_ = -1;  // the first instance in odom, which map instances chain to
  std::unique_ptr<InputRouter> input_;
  // Per input: the sensors (bit i) fusing its samples, one per instance at most.
  std::uint32_t fused_by_[kMaxSensors] = {};
  est::SensorModel models_[kMaxSensors];
  SensorStats stats_[kMaxSensors];
  TimeNs last_arrival_[kMaxSensors] = {};
  // Per input: the navsat sensors (bit j) whose datum heading it gives.
  std::uint32_t heading_targets_[kMaxSensors] = {};
  int num_navsat_ = 0;
  int navsat_sensor_[kMaxNavsatSensors] = {};
  DeviceStatus navsat_layout_[kMaxNavsatSensors];  // names and ids
  DeviceMessage navsat_message_[kMaxNavsatSensors];
  int navsat_message_key_[kMaxNavsatSensors] = {};  // -1 until formatted (configure_navsat)
  static_assert(kMaxSensors <= 32, "heading_targets_ is a bit set");
  // Per imu sensor with standstill_from: its residual gyro bias learner;
  // per input: the sensors whose learner its twist samples teach (bit i).
  std::unique_ptr<est::StandstillGyroBias> standstill_[kMaxSensors];
  std::uint32_t standstill_targets_[kMaxSensors] = {};
  int num_standstill_ = 0;
  int standstill_sensor_[kMaxStandstillLearners] = {};
  DeviceStatus standstill_layout_[kMaxStandstillLearners];  // names and ids
  std::unique_ptr<est::SensorSample[]> staging_;
  int staging_capacity_ = 0;
  std::int64_t set_pose_count_ = 0;
  std::int64_t set_pose_rejected_ = 0;
  std::int64_t fused_total_ = 0;
  std::int64_t lagged_replays_ = 0;
  std::uint64_t seq_ = 0;
  TickDevices* devices_ = nullptr;
  std::int64_t consumed_[kMaxSensors] = {};
  Snapshot scratch_;
  SeqLock<Snapshot> snapshot_;
};

}  // namespace rtfuse
