#pragma once
// The simulated robot's CAN bus, for the loop thread: a MockCanBus with one
// CiA 301/406 encoder node per wheel (hal/mock/canopen_node.hpp) whose shaft
// follows the ground truth. The real encoder driver talks to it unchanged:
// before every send and receive the nodes are put at the true wheel angle of
// the clock's now, so the TPDOs answering a SYNC carry the position at the
// SYNC's time, slip and calibration error included.
//
// Dropouts: a node is off the bus (silent: no heartbeat, no TPDO, deaf to
// NMT) during its window, then comes back as a power-cycled node does: a
// boot-up frame and Pre-operational, waiting for the master's NMT start.
//
// The clock is the real monotonic clock live and a SimClock in lockstep; t0
// is the instant the drive starts. Nothing after construction allocates.
#include <cstdint>
#include <memory>

#include "hal/can_bus.hpp"
#include "hal/clock.hpp"
#include "sim/devices/canopen_encoder_node.hpp"
#include "hal/mock/mock_can_bus.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/truth_source.hpp"
#include "sim/sim_device.hpp"

namespace rtfuse::sim {

// The wheel encoders' counterpart (sim_device.hpp): the configuration's
// [[can.node]]s must be the scenario's encoders, counting the same way.
std::unique_ptr<SimDevice> make_sim_encoders(const SimDeviceContext& ctx, std::string* error);

// The encoder count of `wheel` in `truth`, unwrapped: floor(angle * cpr *
// gear / 2 pi), with angle = rolled distance / true radius, negated for an
// inverted side.
std::int64_t wheel_counts(const RobotBody& robot, const TruthState& truth, int wheel) noexcept;
// The position value an encoder of `bits` reports for unwrapped `counts`:
// [0, 2^bits), or [-2^(bits-1), 2^(bits-1)) when signed.
std::int64_t wrap_position(std::int64_t counts, int bits, bool is_signed) noexcept;

class SimEncoders final : public hal::CanBus, public SimDevice {
 public:
  // `truth` and `clock` must outlive this; `truth` is read on the thread
  // that sends and receives (the loop).
  SimEncoders(const DriveScenario& scenario, TruthSource& truth, const hal::Clock& clock, TimeNs t0);
  ~SimEncoders() override;
  SimEncoders(const SimEncoders&) = delete;
  SimEncoders& operator=(const SimEncoders&) = delete;

  // Puts every node at the truth of `now` after applying the dropout
  // windows that began or ended since the last call. send() and receive()
  // call it with the clock's now; call it yourself only to inspect.
  void update(TimeNs now) noexcept;

  // SimDevice: the loop polls the encoders; nothing to wait for.
  void provide(DeviceBuses& out, hal::Clock& clock) noexcept override;
  TimeNs next_event_time() noexcept override;

  int wheel_count() const noexcept { return wheel_count_; }
  const sim::CanopenEncoderNode& node(int wheel) const noexcept { return *nodes_[wheel]; }
  // The bus for inspection (sent log, pending frames) and fault injection.
  hal::mock::MockCanBus& bus() noexcept { return bus_; }
  const hal::mock::MockCanBus& bus() const noexcept { return bus_; }
  // Times each node was power-cycled back after a dropout.
  int reboots(int wheel) const noexcept { return reboots_[wheel]; }

  // --- faults (the fault-matrix tests drive these from the lockstep loop) -----
  // The wheel's node is off the bus (cable cut) or back on it, without a reboot.
  void set_silent(int wheel, bool silent, TimeNs now) noexcept;
  // The wheel's counter holds its value from `now` on; released, it counts on
  // from where it stopped (a slipping magnet, a frozen encoder ASIC).
  void set_stuck(int wheel, bool stuck, TimeNs now) noexcept;
  // The wheel's counter jumps by `counts` and stays off by that much.
  void jump(int wheel, std::int64_t counts) noexcept;

  // --- hal::CanBus ------------------------------------------------------------
  hal::HalStatus send(const hal::CanFrame& frame) noexcept override;
  int receive(hal::CanFrame* out, int max, TimeNs timeout_ns, hal::HalStatus* status) noexcept override;
  hal::CanBusState state() const noexcept override { return bus_.state(); }
  const char* last_error() const noexcept override { return bus_.last_error(); }

 private:
  struct DropoutEdge {
    TimeNs time = 0;
    int wheel = 0;
    bool begins = false;
  };

  TruthSource& truth_;
  const hal::Clock& clock_;
  TimeNs t0_;
  RobotBody robot_;
  int wheel_count_ = 0;
  hal::mock::MockCanBus bus_;
  std::unique_ptr<sim::CanopenEncoderNode> nodes_[kMaxSimWheels];
  int reboots_[kMaxSimWheels] = {};
  // Counts added to the truth's, and the value a stuck counter holds.
  std::int64_t offset_[kMaxSimWheels] = {};
  bool stuck_[kMaxSimWheels] = {};
  std::int64_t stuck_value_[kMaxSimWheels] = {};
  DropoutEdge edges_[2 * kMaxDropouts];
  int edge_count_ = 0;
  int next_edge_ = 0;
};

}  // namespace rtfuse::sim
