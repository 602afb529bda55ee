#pragma once
// The bus-level simulated robot as one HalBuses: the simulated counterpart
// of each device the configuration drives (encoder nodes on a CAN bus, an
// MPU with a data-ready line, a rendering stereo camera, a u-blox receiver;
// sim_device.hpp), on a clock that is real (rtfused live) or simulated
// (rtfuse-sim, tests). Ground truth is a pure function of time, so both sides, and the
// truth output, agree without sharing state between threads.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hal/clock.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/sim_device.hpp"
#include "sim/truth_trajectory.hpp"

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
  const TruthTrajectory& truth() const { return *truth_; }
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
