#pragma once
// The simulated robot's GNSS receiver, for the GNSS thread: a serial port
// on which a u-blox receiver sends one UBX NAV-PVT per epoch, `latency`
// after it, the antenna's true position (truth through the mounting, on the
// earth at the scenario's origin) plus the errors of a 1 m-class receiver
// (scenario [gnss]). The real GnssReceiver driver runs unchanged on it.
//
// Epoch k is at t_k = t0 + k / rate. A read first puts on the wire every
// epoch whose bytes arrive before the read's deadline, then reads as the
// mock port does (waiting on the clock). Errors: a bias per axis that
// wanders as a first-order Gauss-Markov process (computed epoch after epoch,
// so the receiver has state, as a real one does), white noise, multipath
// jumps (an epoch starts one with probability rate/hour/rate, in a random
// horizontal direction, for multipath_epochs epochs), and outages in which
// it sends fixType 0. Noise is counter-based on (seed, epoch).
//
// Nothing after construction allocates.
#include <cstdint>

#include "estimation/geodesy.hpp"
#include "hal/clock.hpp"
#include "hal/mock/mock_serial_port.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/sim_device.hpp"
#include "sim/truth_source.hpp"

namespace rtfuse::sim {

// The GNSS receiver's counterpart (sim_device.hpp): the scenario must
// carry a receiver, and it speaks UBX.
std::unique_ptr<SimDevice> make_sim_gnss(const SimDeviceContext& ctx, std::string* error);

// The error of epoch k, in ENU metres, and whether the receiver has a fix.
struct SimGnssEpoch {
  TimeNs epoch = 0;
  TimeNs arrival = 0;
  bool fix = true;
  bool multipath = false;
  double truth_enu[3] = {};  // the antenna
  double error_enu[3] = {};
};

class SimGnss final : public hal::SerialPort, public SimDevice {
 public:
  // `truth` and `clock` must outlive this; `truth` is read on the GNSS thread.
  SimGnss(const DriveScenario& scenario, TruthSource& truth, hal::Clock& clock, TimeNs t0);

  // When the next epoch's bytes start to arrive.
  TimeNs next_arrival() const noexcept;

  // SimDevice: its serial port and the robot's clock.
  void provide(DeviceBuses& out, hal::Clock& clock) noexcept override;
  TimeNs next_event_time() noexcept override { return next_arrival(); }
  // What epoch k is (errors included), for k at or after the last epoch
  // asked for or sent (the receiver's error has state: it advances to k).
  const SimGnssEpoch& epoch(std::int64_t k) noexcept;
  const est::LocalTangentPlane& plane() const noexcept { return plane_; }
  std::int64_t epochs_sent() const noexcept { return next_; }

  int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, hal::HalStatus* status) noexcept override;
  // Configuration messages are taken and ignored, as a receiver that
  // already runs the configuration it is sent.
  hal::HalStatus write(const std::uint8_t* data, int size) noexcept override;
  const char* last_error() const noexcept override { return port_.last_error(); }
  bool reopen() noexcept override { return port_.reopen(); }

 private:
  void send(std::int64_t k) noexcept;
  bool in_outage(double t_s) const noexcept;

  const SimGnssConfig cfg_;
  TruthSource& truth_;
  hal::Clock& clock_;
  TimeNs t0_;
  std::uint64_t seed_;
  TimeNs period_ns_;
  TimeNs latency_ns_;
  est::LocalTangentPlane plane_;
  hal::mock::MockSerialPort port_;
  std::int64_t next_ = 0;  // the next epoch to put on the wire
  // The error state, advanced epoch by epoch.
  std::int64_t state_epoch_ = -1;
  double bias_[3] = {};
  std::int64_t multipath_left_ = 0;
  double multipath_dir_[2] = {};
  SimGnssEpoch current_;
  std::uint8_t frame_[100] = {};
};

}  // namespace rtfuse::sim
