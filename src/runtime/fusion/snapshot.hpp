#pragma once
// What the loop publishes to the rest of the process after every tick, through
// a SeqLock: plain arrays only, so it is trivially copyable.
#include <cstdint>

#include "runtime/config/config.hpp"
#include "runtime/fusion/device_status.hpp"
#include "runtime/fusion/nav_snapshot.hpp"

namespace rtfuse {

struct SensorStats {
  std::int64_t last_stamp_ns = 0;
  double rate_hz = 0.0;
  std::int64_t received = 0;
  std::int64_t accepted = 0;
  std::int64_t rejected_mahalanobis = 0;
  std::int64_t rejected_invalid = 0;   // NaN/Inf, bad covariance, no transform, out of order, stamped ahead
  std::int64_t rejected_stale = 0;     // older than the history
  std::int64_t rejected_overflow = 0;  // ring full: the loop fell behind
  std::int64_t rejected_rate = 0;      // beyond the sensor's max_rate, not decoded
  std::int64_t rejected_oversize = 0;  // above [lcm] max_message_bytes, not decoded
  std::int64_t decode_errors = 0;
  std::int64_t yaw_conflicts = 0;
  std::int64_t timeouts = 0;
  bool timed_out = false;
};

// Every message of a sensor that did not reach the filter or was refused by it.
inline std::int64_t rejected_total(const SensorStats& st) noexcept {
  return st.rejected_mahalanobis + st.rejected_invalid + st.rejected_stale + st.rejected_overflow +
         st.rejected_rate + st.rejected_oversize + st.decode_errors;
}

struct LoopStats {
  double rate_hz = 0.0;
  std::int64_t period_ns = 0;
  std::int64_t ticks = 0;
  std::int64_t overruns = 0;
  std::int64_t jitter_mean_ns = 0;
  std::int64_t jitter_max_ns = 0;
  std::int64_t tick_duration_mean_ns = 0;
  std::int64_t tick_duration_max_ns = 0;
  std::int64_t measurements_fused = 0;
  std::int64_t lagged_replays = 0;
};

// Dead reckoning from the wheels alone (exact arc integration of the
// encoders' twist), published as "raw wheel odometry" to compare against.
struct WheelOdometrySnapshot {
  bool valid = false;
  std::int64_t stamp_ns = 0;
  double x = 0, y = 0, yaw = 0;
  double vx = 0, vyaw = 0;
  double var_vx = 0, var_vyaw = 0;
};

// One filter instance's estimate and what is derived from it. For the first
// instance the estimate is Snapshot's own fields (stamp_ns ... covariance)
// and only map_odom and the filtered fix are filled here.
struct InstanceSnapshot {
  std::int64_t stamp_ns = 0;
  bool initialized = false;
  // A map instance with a navsat sensor before its first fused fix: its
  // outputs wait, so nobody sees a map -> odom that nothing anchors.
  bool awaiting_fix = false;
  double state[15] = {};
  double covariance[225] = {};
  std::int64_t fixes_fused = 0;
  // map -> odom (a map instance, with a local instance to chain to): this
  // instance's map -> base_link times the local odom -> base_link inverted,
  // both at this instance's stamp, as robot_localization's global node does.
  bool has_map_odom = false;
  double map_odom_translation[3] = {};
  double map_odom_rotation[4] = {0.0, 0.0, 0.0, 1.0};  // x y z w
  // navsat_transform's filtered fix: this instance's position as a fix.
  bool has_filtered_fix = false;
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
  double fix_covariance[9] = {};  // east north up, m², row-major
};

struct Snapshot {
  std::int64_t tick_time_ns = 0;   // loop clock when the snapshot was taken
  std::int64_t stamp_ns = 0;       // time the estimate is valid at (last measurement)
  std::uint64_t seq = 0;
  bool initialized = false;
  bool awaiting_fix = false;       // the first instance's (InstanceSnapshot::awaiting_fix)
  double state[15] = {};
  double covariance[225] = {};     // row-major
  int num_instances = 1;
  InstanceSnapshot instances[kMaxInstances];
  LoopStats loop;
  std::int64_t unknown_channel_messages = 0;
  std::int64_t set_pose_count = 0;
  std::int64_t set_pose_rejected = 0;  // malformed, oversize, ring full, or a frame not connected to the world frame
  std::int64_t set_pose_ignored = 0;   // [publish] accept_set_pose = false
  int num_sensors = 0;
  SensorStats sensors[kMaxSensors];
  int num_devices = 0;
  DeviceStatus devices[kMaxDevices];
  WheelOdometrySnapshot wheel_odometry;
  NavSnapshot nav;
};

}  // namespace rtfuse
