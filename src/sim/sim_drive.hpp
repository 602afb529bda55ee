#pragma once
// A whole drive of the simulated robot in lockstep on a simulated clock, as
// fast as the CPU allows: the same Hardware (drivers), FusionCore and
// Publisher as rtfused, on the simulated buses, optionally recorded as a HAL
// recording (bus events, ticks, outputs, ground truth) that rtfuse-replay
// reproduces byte for byte. Used by rtfuse-sim, the drive-scenario tests and
// the benchmarks.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/config/config.hpp"
#include "runtime/fusion/snapshot.hpp"
#include "sim/goal_sequence.hpp"
#include "sim/truth_trajectory.hpp"

namespace rtfuse {
class Hardware;
}

namespace rtfuse::sim {

class SimRobot;

struct DriveOptions {
  std::string scenario_path;  // empty: the config's [hardware] scenario
  std::string record_path;    // empty: no recording
  std::string config_text;    // stored in the recording
  double truth_rate_hz = 50.0;
  // Called at every tick time t before the devices and the loop run up to
  // it: the fault-matrix tests inject faults into the robot's devices here
  // (everything runs on this one thread in lockstep).
  std::function<void(TimeNs t, SimRobot& robot)> before_tick;
  // Every 1/truth_rate_hz: t, the truth and each instance's x y yaw (and a
  // map instance's map -> odom x y yaw) as one CSV line to this file; empty:
  // none. For the drive tests' time-based checks (recovery after an outage).
  std::string trace_path;
  // Called after the loop's tick at t with what it published and the truth.
  std::function<void(TimeNs t, const Snapshot& snapshot, const TruthState& truth)> after_tick;
  // Called once the drive is over (the workers finished) with the devices,
  // for a tool's files of the mapper's map or the navigator's costmap.
  std::function<void(Hardware& hardware)> at_end;
};

// One filter instance's position error against ground truth, sampled every
// tick once it publishes (a map instance: after its first fix). The truth's
// frame is odom's at the start; a map instance matches it when its datum is
// the start with the heading east.
struct InstanceErrors {
  std::int64_t samples = 0;
  double final_error_m = 0.0;
  double rms_error_m = 0.0;
  double final_yaw_error_rad = 0.0;
  double max_error_m = 0.0;
  // The largest change of the position error from one tick to the next: a
  // jump of the estimate that the robot did not make.
  double max_jump_m = 0.0;
  // map -> odom's largest change from one tick to the next (map instances).
  double max_map_odom_step_m = 0.0;
};

struct DriveResult {
  bool ok = false;
  std::string error;
  std::int64_t ticks = 0;
  double duration_s = 0.0;
  // Position error against ground truth, sampled every tick once the filter
  // is initialised; and the same for raw wheel odometry (dead reckoning).
  double final_error_m = 0.0;
  double rms_error_m = 0.0;
  double final_yaw_error_rad = 0.0;
  double max_error_m = 0.0;
  // The largest change of the position error from one tick to the next: a
  // jump of the estimate that the robot did not make.
  double max_jump_m = 0.0;
  double raw_final_error_m = 0.0;
  double raw_rms_error_m = 0.0;
  // Every instance's (the first's are the fields above too).
  int num_instances = 1;
  InstanceErrors instances[kMaxInstances];
  Snapshot final;
  std::int64_t recording_lost = 0;  // events the recorder had no room for (must be 0)
  // A commanded drive: each scenario goal's fate, and the true centre's
  // nearest approach to any [[obstacle]] box over every tick (infinity
  // without obstacles).
  std::vector<GoalOutcome> goals;
  int goals_reached = 0;
  double min_obstacle_distance_m = 0.0;
  std::int64_t commands = 0;       // velocity commands handed to the base
  std::int64_t late_commands = 0;  // SimRobot::commanded_counters(): must be 0 in lockstep
  std::int64_t watchdog_stops = 0;
  std::int64_t history_misses = 0;  // truth asked for before a reader's history (must be 0)
};

struct DriveProgress {
  double sim_time_s = 0.0;
  double duration_s = 0.0;
};

DriveResult run_sim_drive(const RuntimeConfig& cfg, const DriveOptions& options,
                                const std::function<void(const DriveProgress&)>& progress);

}  // namespace rtfuse::sim
