#pragma once
// The validated, fixed-size configuration. Parsed once from TOML before
// start(); nothing is parsed afterwards. Schema: docs/configuration.md.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/fixed_string.hpp"
#include "estimation/filter_params.hpp"
#include "estimation/standstill_gyro_bias.hpp"
#include "geometry/rigid_transform.hpp"
#include "runtime/config/hardware_config.hpp"
#include "runtime/config/name.hpp"

namespace rtfuse {

constexpr int kMaxSensors = 16;
// GNSS receivers a robot carries (a dual-antenna set-up at most).
constexpr int kMaxNavsatSensors = 2;
// imu sensors with standstill_from (a residual gyro bias learner each).
constexpr int kMaxStandstillLearners = 4;
constexpr int kMaxStaticTransforms = 24;
// Filter instances in one process: robot_localization's dual EKF (a local
// one in odom, a global one in map) and one more, e.g. to compare tunings.
constexpr int kMaxInstances = 3;


// Where a sensor's samples come from: decoded LCM messages, or a source of
// one of the devices this process drives (an index into the registry's
// sources, devices/device_registry.hpp).
using SensorSource = std::int8_t;
constexpr SensorSource kLcmSource = -1;

struct SensorConfig {
  Name name;        // "odom0", "imu0", ... (robot_localization's sensor names)
  Name channel;     // LCM channel (the ROS topic, unchanged); empty for drivers
  SensorSource source = kLcmSource;
  est::SensorParams params;
  // LCM sensors: messages beyond this rate (a burst of one ring, 2 x
  // queue_size, allowed) are dropped before decoding and counted. The loader
  // resolves an absent key to what the loop drains, 2 x queue_size per tick.
  double max_rate_hz = 0.0;
  // type "navsat": the antenna's frame (its lever arm from base_link; empty:
  // at base_link's origin) and the IMU sensor whose orientation gives the
  // datum's heading (-1: the filter's own yaw or a configured datum).
  Name antenna_frame;
  Name heading_imu;
  int heading_sensor = -1;
  // type "imu": the odometry or twist sensor whose standstills teach the
  // gyro's residual bias (empty: none), resolved to its index, and the
  // learner's parameters (estimation/standstill_gyro_bias.hpp).
  Name standstill_from;
  int standstill_sensor = -1;
  est::StandstillBiasParams standstill;
  // The filter instance that fuses it (0: [filter] and the top-level
  // [[sensor]]s; k: the k-th [[instance]] after it).
  int instance = 0;
  // The sensor whose ring carries its samples: itself (-1, or its own index)
  // or an earlier one of another instance on the same source, so that one
  // message or one driver feeds every instance that fuses it.
  int input = -1;
};

struct StaticTransformConfig {
  Name parent;
  Name child;
  geometry::RigidTransform parent_T_child;  // pose of child in parent
};

struct RealtimeConfig {
  bool lock_memory = false;   // mlockall(MCL_CURRENT | MCL_FUTURE)
  int priority = 0;           // SCHED_FIFO priority of the loop, 0 = leave SCHED_OTHER
  // SCHED_FIFO priority of the threads the loop depends on (devices, LCM
  // input, publisher), below the loop's; 0 = SCHED_OTHER. Without it a busy
  // process starves them even when the loop keeps time: stale sensors, late
  // outputs (docs/reliability.md, the CPU hog).
  int io_priority = 0;
  int cpu = -1;               // pin the loop to this CPU, -1 = no affinity
  bool require = false;       // exit instead of warning when the OS refuses
};

struct PublishConfig {
  Name odometry_channel{"rtfuse/odometry"};
  Name pose_channel{"rtfuse/pose"};
  Name tf_channel{"rtfuse/tf"};
  Name state_channel{"rtfuse/state"};
  Name diagnostics_channel{"rtfuse/diagnostics"};
  Name set_pose_channel{"rtfuse/set_pose"};
  // set_pose resets the estimate, and LCM has no authentication: anyone on
  // the multicast group could send it. Ignored (and counted) unless enabled.
  bool accept_set_pose = false;
  double odometry_rate_hz = 50.0;
  double pose_rate_hz = 50.0;
  double tf_rate_hz = 50.0;
  double state_rate_hz = 10.0;
  double diagnostics_rate_hz = 1.0;
  bool publish_tf = true;
};

// A filter instance after the first (the first is [filter], world_frame and
// the top-level sensors): its own EKF, sensors, and outputs under
// rtfuse/<name>/. docs/configuration.md, "[[instance]]".
struct InstanceConfig {
  Name name{"local"};
  Name world_frame{"map"};
  est::FilterParams filter;  // [filter]'s values where the instance gives none
  Name odometry_channel;     // rtfuse/<name>/odometry ...
  Name pose_channel;
  Name state_channel;
  Name filtered_fix_channel;  // rtfuse/<name>/gps/filtered (navsat sensors only)
  double odometry_rate_hz = 50.0;
  double pose_rate_hz = 50.0;
  double state_rate_hz = 10.0;
  double tf_rate_hz = 50.0;   // map -> odom on [publish] tf_channel
  double filtered_fix_rate_hz = 10.0;
};

// The built-in simulated robot (config/sim.toml): a figure-eight drive with
// ground truth, publishing imu_t and odometry_t on the sensors' channels.
struct SimLcmConfig {
  bool enabled = false;
  std::uint64_t seed = 1;
  double figure_eight_radius_m = 3.0;
  double speed_mps = 1.0;
  double imu_rate_hz = 100.0;
  double odom_rate_hz = 50.0;
  Name imu_channel{"imu/data"};
  Name odom_channel{"wheel/odom"};
  Name truth_channel{"sim/ground_truth"};
  double gyro_noise_rad_s = 0.005;
  double gyro_bias_rad_s = 0.01;
  double accel_noise_mps2 = 0.05;
  double accel_bias_mps2 = 0.05;
  double orientation_noise_rad = 0.01;
  // The IMU's own yaw, as a magnetometer-aided AHRS reports it: an error that
  // wanders (first-order Gauss-Markov) but stays bounded.
  double yaw_error_rad = 0.02;     // its standard deviation
  double yaw_error_time_s = 30.0;  // its correlation time
  double odom_speed_noise_mps = 0.02;
  double odom_yaw_rate_noise_rad_s = 0.02;
  double wheel_slip = 0.03;   // fractional speed error (scale), as on a real floor
};

struct RuntimeConfig {
  std::string source;        // file the config came from ("<embedded sim.toml>" ...)
  double rate_hz = 200.0;    // [filter] frequency
  Name world_frame{"odom"};
  Name odom_frame{"odom"};
  Name base_link_frame{"base_link"};
  Name map_frame{"map"};
  est::FilterParams filter;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  // Largest input message taken from LCM; larger ones are dropped undecoded
  // and counted (every input type is well under 1 KiB with short frame names).
  int lcm_max_message_bytes = 4096;
  // An LCM input stamped more than this after its arrival is dropped
  // (counted as invalid): [lcm] max_stamp_ahead, seconds.
  TimeNs lcm_max_stamp_ahead_ns = 500'000'000;
  RealtimeConfig realtime;
  PublishConfig publish;
  std::array<SensorConfig, kMaxSensors> sensors{};
  int num_sensors = 0;
  std::array<StaticTransformConfig, kMaxStaticTransforms> static_transforms{};
  int num_static_transforms = 0;
  SimLcmConfig sim;
  HardwareConfig hardware;
  // instances[0] holds the first instance's name and filtered-fix channel
  // only: its filter and frame are `filter` and `world_frame` above.
  std::array<InstanceConfig, kMaxInstances> instances{};
  int num_instances = 1;
};

inline const est::FilterParams& instance_filter(const RuntimeConfig& c, int k) {
  return k == 0 ? c.filter : c.instances[static_cast<std::size_t>(k)].filter;
}
inline const Name& instance_world_frame(const RuntimeConfig& c, int k) {
  return k == 0 ? c.world_frame : c.instances[static_cast<std::size_t>(k)].world_frame;
}
// The index of the sensor whose ring carries sensor i's samples.
inline int sensor_input(const RuntimeConfig& c, int i) {
  const int in = c.sensors[static_cast<std::size_t>(i)].input;
  return in < 0 ? i : in;
}
// "odom0" for the first instance's sensors, "global/odom0" for the others':
// the name in diagnostics and the replay's JSON.
inline Name qualified_sensor_name(const RuntimeConfig& c, int i) {
  const SensorConfig& s = c.sensors[static_cast<std::size_t>(i)];
  if (s.instance == 0) return s.name;
  // Truncated past Name's capacity (the explicit constructor cuts).
  return Name(std::string(c.instances[static_cast<std::size_t>(s.instance)].name.view()) + "/" +
              std::string(s.name.view()));
}

}  // namespace rtfuse
