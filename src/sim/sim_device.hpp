#pragma once
// A simulated device on the mock HAL: the counterpart of one registered
// runtime device (runtime/devices/device_registry.cpp), answering its driver
// on the same kinds of bus the kernel would give it. The simulated robot
// makes the counterpart of every device the configuration drives, by the
// device's name, from sim_device_registry.cpp, and steps nothing itself:
// the drivers pull, as they would from hardware.
#include <memory>
#include <string>
#include <string_view>

#include "hal/clock.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/device_buses.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/truth_source.hpp"

namespace rtfuse::sim {

// What a counterpart is made from. Everything outlives it.
struct SimDeviceContext {
  const RuntimeConfig& cfg;
  const DriveScenario& scenario;
  const std::string& scenario_path;  // in messages
  // This device's own: a commanded robot's truth advances per reader, and
  // each device reads it on its driver's thread.
  TruthSource& truth;
  hal::Clock& clock;
  TimeNs t0;
};

class SimDevice {
 public:
  virtual ~SimDevice() = default;
  // The buses its runtime device's driver talks to; `clock` is the robot's.
  virtual void provide(DeviceBuses& out, hal::Clock& clock) noexcept = 0;
  // When it next has something for its driver (a data-ready edge, a frame's
  // end of exposure, a fix's first byte): the lockstep drive steps the
  // device's thread up to each tick with it. Polled devices: never.
  virtual TimeNs next_event_time() noexcept = 0;
};

// The counterpart of the registered device `device`: made by `create`,
// which checks that the robot configuration can talk to the simulated one
// (node ids, addresses, protocols) and says in *error what does not fit.
struct SimCounterpart {
  const char* device;
  std::unique_ptr<SimDevice> (*create)(const SimDeviceContext& ctx, std::string* error);
};

// Null when the simulator has no counterpart of that device.
const SimCounterpart* find_sim_counterpart(std::string_view device) noexcept;

}  // namespace rtfuse::sim
