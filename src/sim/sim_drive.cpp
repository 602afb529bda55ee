#include "sim/sim_drive.hpp"

#include <algorithm>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <thread>

#include "hal/mock/sim_clock.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "sim/ground_truth.hpp"
#include "sim/sim_robot.hpp"

namespace rtfuse::sim {
namespace {

class NullSink final : public MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, TimeNs) override { return true; }
};

double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

// An instance's running error sums.
struct ErrorSums {
  double sum_sq = 0.0;
  double last_ex = 0.0, last_ey = 0.0;
  double last_map_odom[3] = {};
  bool has_map_odom = false;
};

void accumulate(const Snapshot& snap, int k, const TruthState& truth, ErrorSums& sums, InstanceErrors& out) {
  const InstanceSnapshot& in = snap.instances[k];
  const bool publishes = k == 0 ? snap.initialized && !snap.awaiting_fix : in.initialized && !in.awaiting_fix;
  if (!publishes) return;
  const double* x = k == 0 ? snap.state : in.state;
  const double ex = x[0] - truth.x, ey = x[1] - truth.y;
  const double e = std::hypot(ex, ey);
  if (out.samples > 0) out.max_jump_m = std::max(out.max_jump_m, std::hypot(ex - sums.last_ex, ey - sums.last_ey));
  sums.last_ex = ex;
  sums.last_ey = ey;
  out.max_error_m = std::max(out.max_error_m, e);
  sums.sum_sq += e * e;
  ++out.samples;
  out.final_error_m = e;
  out.final_yaw_error_rad = std::abs(wrap(x[5] - truth.yaw));
  if (in.has_map_odom) {
    if (sums.has_map_odom) {
      out.max_map_odom_step_m =
          std::max(out.max_map_odom_step_m, std::hypot(in.map_odom_translation[0] - sums.last_map_odom[0],
                                                       in.map_odom_translation[1] - sums.last_map_odom[1]));
    }
    for (int a = 0; a < 3; ++a) sums.last_map_odom[a] = in.map_odom_translation[a];
    sums.has_map_odom = true;
  }
}

// The distance from a point to an axis-aligned box's footprint (0 inside).
double box_distance(const ObstacleBox& b, double x, double y) {
  const double dx = std::max(std::abs(x - b.x) - 0.5 * b.size_x, 0.0);
  const double dy = std::max(std::abs(y - b.y) - 0.5 * b.size_y, 0.0);
  return std::sqrt(dx * dx + dy * dy);
}

double yaw_of(const double q[4]) {
  return std::atan2(2.0 * (q[3] * q[2] + q[0] * q[1]), 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]));
}

}  // namespace

DriveResult run_sim_drive(const RuntimeConfig& cfg, const DriveOptions& options,
                                const std::function<void(const DriveProgress&)>& progress) {
  DriveResult result;
  // Away from 0 so no stamp is ever mistaken for "unset".
  const TimeNs t0 = 1'000'000'000;
  hal::mock::SimClock clock(t0);
  std::string error;
  std::unique_ptr<SimRobot> robot = SimRobot::create(cfg, options.scenario_path, clock, t0, &error);
  if (!robot) {
    result.error = error;
    return result;
  }
  NullSink null_sink;
  PipelineOptions pipeline_options;
  pipeline_options.record_path = options.record_path;
  pipeline_options.config_text = options.config_text;
  pipeline_options.record_clock = &clock;
  pipeline_options.start_ns = t0;
  pipeline_options.sink = &null_sink;
  std::unique_ptr<TickPipeline> pipeline = TickPipeline::create(cfg, robot->buses(), pipeline_options, &error);
  if (!pipeline || !pipeline->start(t0, &error)) {
    result.error = error;
    return result;
  }
  RecordingTap* tap = pipeline->tap();
  DirectOutput output(pipeline->publisher(), pipeline->sink());

  const TimeNs period = static_cast<TimeNs>(std::llround(1e9 / cfg.rate_hz));
  const TimeNs truth_period = static_cast<TimeNs>(std::llround(1e9 / options.truth_rate_hz));
  const double duration = robot->duration_s();
  const TimeNs end = t0 + sec_to_ns(duration);
  GroundTruthEncoder truth_encoder;
  TimeNs next_truth = t0;
  LoopStats loop;
  loop.rate_hz = cfg.rate_hz;
  loop.period_ns = period;
  double raw_sum_sq = 0.0;
  std::int64_t raw_samples = 0;
  result.num_instances = pipeline->core().num_instances();
  ErrorSums sums[kMaxInstances];
  std::FILE* trace = nullptr;
  if (!options.trace_path.empty()) {
    trace = std::fopen(options.trace_path.c_str(), "w");
    if (trace == nullptr) {
      result.error = options.trace_path + ": cannot write the trace: " + std::strerror(errno);
      return result;
    }
    std::fprintf(trace, "t,truth_x,truth_y,truth_yaw");
    for (int k = 0; k < result.num_instances; ++k) {
      const char* name = cfg.instances[static_cast<std::size_t>(k)].name.c_str();
      std::fprintf(trace, ",%s_x,%s_y,%s_yaw,%s_map_odom_x,%s_map_odom_y,%s_map_odom_yaw", name, name, name, name,
                   name, name);
    }
    std::fprintf(trace, "\n");
  }
  DriveProgress prog;
  prog.duration_s = duration;
  // A commanded drive: goals in as LCM messages through the pipeline (so
  // a recording keeps them), commands out to the base.
  GoalSequence goals(robot->scenario().goals, t0);
  const int goal_input =
      pipeline->hardware() != nullptr ? pipeline->hardware()->find_input(cfg.hardware.navigation.goal_channel.view()) : -1;
  result.min_obstacle_distance_m = std::numeric_limits<double>::infinity();
  for (TimeNs t = t0; t <= end; t += period) {
    // Let the writer catch up: in lockstep nothing may be lost.
    while (tap && tap->recorder().backlogged()) std::this_thread::sleep_for(std::chrono::microseconds(200));
    clock.set(t);
    if (options.before_tick) {
      options.before_tick(t, *robot);
      clock.set(t);
    }
    // Each device thread's events up to this tick, as it would have handled
    // them before the loop woke. Bounded: a driver that is down (re-init
    // backing off) does not wait, and the event time would not move.
    for (int d = 0; d < pipeline->thread_device_count(); ++d) {
      Device& device = pipeline->thread_device(d);
      const char* name = pipeline->thread_device_name(d);
      for (int k = 0; k < 64; ++k) {
        const TimeNs due = robot->next_event_time(name);
        if (due > t) break;
        device.step(kDeviceStepTimeoutNs);
        clock.set(t);
        // No progress (the device is down, its driver backing off between
        // reopens): once per tick, as its thread would wake about once per
        // tick; more would run the backoff on a clock that cannot advance.
        if (robot->next_event_time(name) == due) break;
      }
      clock.set(t);
    }
    ++loop.ticks;
    pipeline->step(t, loop, output);
    if (Hardware* hw = pipeline->hardware()) hw->step_workers();
    const Snapshot& snap = pipeline->core().last_snapshot();
    const TruthState truth = robot->truth_at(t);
    if (options.after_tick) options.after_tick(t, snap, truth);
    if (robot->commanded()) {
      // Issued at the tick; the base acts on it command_latency later, so
      // no device has read the truth past that yet.
      if (snap.nav.command_due && snap.nav.send_command) {
        robot->commands().push(BaseCommand{t, snap.nav.linear_mps, snap.nav.angular_rps});
        ++result.commands;
      }
      DriveGoal g;
      if (goal_input >= 0 && goals.step(t, snap.initialized, snap.nav, truth, &g)) {
        const std::vector<std::uint8_t> b = encode_goal(g, cfg.world_frame.c_str(), t);
        pipeline->deliver_input(goal_input, b.data(), static_cast<int>(b.size()), t);
      }
    }
    for (const ObstacleBox& b : robot->scenario().obstacles) {
      result.min_obstacle_distance_m = std::min(result.min_obstacle_distance_m, box_distance(b, truth.x, truth.y));
    }
    if (t >= next_truth) {
      next_truth += truth_period;
      int size = 0;
      const std::uint8_t* bytes = truth_encoder.encode(truth, t, &size);
      if (tap && size > 0) tap->recorder().record_output(kGroundTruthChannel, bytes, size, t);
      if (trace != nullptr) {
        std::fprintf(trace, "%.3f,%.4f,%.4f,%.5f", ns_to_sec(t - t0), truth.x, truth.y, truth.yaw);
        for (int k = 0; k < result.num_instances; ++k) {
          const InstanceSnapshot& in = snap.instances[k];
          const bool publishes = k == 0 ? snap.initialized && !snap.awaiting_fix : in.initialized && !in.awaiting_fix;
          const double* x = k == 0 ? snap.state : in.state;
          if (publishes) {
            std::fprintf(trace, ",%.4f,%.4f,%.5f", x[0], x[1], x[5]);
          } else {
            std::fprintf(trace, ",,,");
          }
          if (in.has_map_odom) {
            std::fprintf(trace, ",%.4f,%.4f,%.5f", in.map_odom_translation[0], in.map_odom_translation[1],
                         yaw_of(in.map_odom_rotation));
          } else {
            std::fprintf(trace, ",,,");
          }
        }
        std::fprintf(trace, "\n");
      }
    }
    for (int k = 0; k < result.num_instances; ++k) accumulate(snap, k, truth, sums[k], result.instances[k]);
    if (snap.wheel_odometry.valid) {
      const double e = std::hypot(snap.wheel_odometry.x - truth.x, snap.wheel_odometry.y - truth.y);
      raw_sum_sq += e * e;
      ++raw_samples;
      result.raw_final_error_m = e;
    }
    ++result.ticks;
    if (progress && result.ticks % 2000 == 0) {
      prog.sim_time_s = ns_to_sec(t - t0);
      progress(prog);
    }
  }
  if (Hardware* hw = pipeline->hardware()) {
    hw->finish_workers();
    if (options.at_end) options.at_end(*hw);
  }
  result.duration_s = duration;
  result.goals = goals.outcomes();
  result.goals_reached = goals.reached();
  if (robot->commanded()) {
    const SimRobot::CommandedCounters c = robot->commanded_counters();
    result.late_commands = c.late_commands;
    result.watchdog_stops = c.watchdog_stops;
    result.history_misses = c.history_misses + c.far_queries + c.feed_overruns;
  }
  for (int k = 0; k < result.num_instances; ++k) {
    InstanceErrors& e = result.instances[k];
    e.rms_error_m = e.samples > 0 ? std::sqrt(sums[k].sum_sq / static_cast<double>(e.samples)) : 0.0;
  }
  const InstanceErrors& first = result.instances[0];
  result.final_error_m = first.final_error_m;
  result.rms_error_m = first.rms_error_m;
  result.final_yaw_error_rad = first.final_yaw_error_rad;
  result.max_error_m = first.max_error_m;
  result.max_jump_m = first.max_jump_m;
  if (trace != nullptr && std::fclose(trace) != 0) {
    result.error = options.trace_path + ": writing the trace: " + std::strerror(errno);
    return result;
  }
  result.raw_rms_error_m = raw_samples > 0 ? std::sqrt(raw_sum_sq / static_cast<double>(raw_samples)) : 0.0;
  pipeline->core().snapshot().load(result.final);
  // The workers' health after finishing (a mapper's last keyframes).
  if (Hardware* hw = pipeline->hardware()) hw->fill_snapshot(result.final);
  if (tap) {
    result.recording_lost = tap->overflows();
    if (!pipeline->stop(&error)) {
      result.error = "writing the recording: " + error;
      return result;
    }
  }
  result.ok = true;
  return result;
}

}  // namespace rtfuse::sim
