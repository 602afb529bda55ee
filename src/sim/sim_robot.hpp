#pragma once
// The bus-level simulated robot as one HalBuses: the simulated counterpart
// of each device the configuration drives (encoder nodes on a CAN bus, an
// MPU with a data-ready line, a rendering stereo camera, a u-blox receiver;
// sim_device.hpp), on a clock that is real (rtfused live) or simulated
// (rtfuse-sim, tests). A scripted drive's ground truth is a pure function of time, so
// both sides, and the truth output, agree without sharing state between threads.
//
// A commanded drive ([drive] mode = "commanded") has no scripted path: its
// base follows the velocity commands pushed into commands(), and each
// device (and the robot's own truth_at) integrates them with a
// CommandedTruth of its own (commanded_base.hpp), so the threads still
// share nothing but the lock-free feed.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hal/clock.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "sim/commanded_base.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/sim_device.hpp"
#include "sim/truth_trajectory.hpp"
#include "sim/wheel_slip_model.hpp"

namespace rtfuse::sim {

class SimRobot {
 public:
  // Loads the scenario named by cfg.hardware.scenario (or `scenario_path`
  // when given) and makes the simulated counterpart of every device the
  // configuration drives (sim_device_registry.cpp), each checking that the
  // robot configuration can talk to it (node ids, addresses, protocols).
  // scenario_text, when not null, is the scenario itself (a built-in one)
  // and scenario_path only names it in messages.
  static std::unique_ptr<SimRobot> create(const RuntimeConfig& cfg, const std::string& scenario_path,
                                                hal::Clock& clock, TimeNs t0, std::string* error,
                                                const std::string_view* scenario_text = nullptr);

  HalBuses buses();
  const DriveScenario& scenario() const { return scenario_; }
  // The scripted drive's truth (a commanded drive's robot rests in it:
  // use truth_at()).
  const TruthTrajectory& truth() const { return *truth_; }

  // --- a commanded drive ([drive] mode = "commanded") ---------------------
  bool commanded() const noexcept { return scenario_.mode == DriveMode::kCommanded; }
  // Where the velocity commands go (one producer thread). Only when
  // commanded().
  CommandFeed& commands() noexcept { return *commands_; }
  // The goals the navigator is given, in order (empty for a scripted drive).
  const std::vector<DriveGoal>& goals() const noexcept { return scenario_.goals; }
  // The truth reader of the device `name` ("imu", "wheel_encoders",
  // "camera", "gnss"); null when not commanded() or no such device. Its
  // counters say whether the run was deterministic.
  const CommandedTruth* device_truth(std::string_view name) const noexcept;
  // truth_at()'s reader; null when not commanded().
  const CommandedTruth* own_truth() const noexcept { return own_truth_.get(); }
  // One more reader, for a thread other than the drive's that wants the
  // truth (a status line, a truth publisher). Setup time: allocates.
  // Null when not commanded().
  std::unique_ptr<CommandedTruth> make_truth_reader() const;
  // Sums over every reader of this robot: any late command or overrun
  // means the readers may disagree. watchdog_stops is truth_at()'s reader's.
  struct CommandedCounters {
    std::int64_t late_commands = 0;
    std::int64_t feed_overruns = 0;
    std::int64_t history_misses = 0;
    std::int64_t far_queries = 0;
    std::int64_t watchdog_stops = 0;
    std::int64_t rejected_commands = 0;   // issued before an accepted one
    std::int64_t non_finite_commands = 0;  // stored as a stop
  };
  CommandedCounters commanded_counters() const noexcept;
  // The counterpart of the registered device `name` as its type (SimImu for
  // "imu", SimEncoders, SimCamera, SimGnss); null when the configuration
  // has no such device. For fault injection and inspection.
  template <class T>
  T* device(std::string_view name) noexcept {
    const int i = find_device_type(name);
    return i < 0 ? nullptr : dynamic_cast<T*>(devices_[i].get());
  }
  TimeNs start_time() const { return t0_; }
  // The drive's length (scenario duration, or the path's).
  double duration_s() const;
  // The truth for the drive's thread (the lockstep loop). A commanded
  // robot integrates it in its own reader: call it from one thread only,
  // at times that go back no more than its history (256 ms), and give
  // another thread a make_truth_reader() of its own.
  TruthState truth_at(TimeNs t) const noexcept;
  // When the counterpart of the thread device `name` ("imu", "camera")
  // next has something for its driver; far in the future for a device this
  // robot does not simulate. The lockstep drive steps each thread device up
  // to the tick with it.
  TimeNs next_event_time(std::string_view name) noexcept;

 private:
  SimRobot() = default;
  std::string scenario_path_;
  DriveScenario scenario_;
  std::unique_ptr<TruthTrajectory> truth_;
  // A commanded drive's: the slip all readers share, the feed, a reader per
  // device (at its registry index) and one for truth_at().
  std::unique_ptr<WheelSlipModel> slip_;
  std::unique_ptr<CommandFeed> commands_;
  std::unique_ptr<CommandedTruth> device_truth_[kMaxDeviceTypes];
  std::unique_ptr<CommandedTruth> own_truth_;
  std::unique_ptr<SimDevice> devices_[kMaxDeviceTypes];  // at their registry index
  hal::Clock* clock_ = nullptr;
  TimeNs t0_ = 0;
};

// Encodes ground-truth odometry_t into a buffer sized once: no allocation per message.
class GroundTruthEncoder {
 public:
  GroundTruthEncoder();
  // Bytes valid until the next call; size in *size.
  const std::uint8_t* encode(const TruthState& truth, TimeNs stamp, int* size) noexcept;

 private:
  rtfuse::odometry_t msg_{};
  std::vector<std::uint8_t> buf_;
  std::int32_t seq_ = 0;
};

}  // namespace rtfuse::sim
