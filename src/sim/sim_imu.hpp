#pragma once
// The simulated robot's IMU, for the IMU thread: the I2C bus with an MPU
// register file on it (hal/mock/mpu_register_file.hpp) and the chip's
// data-ready line. The real IMU driver runs unchanged: it waits for an edge,
// then burst-reads the data registers.
//
// Sample k is taken at t_k = t0 + k / rate. wait_edge() sleeps (through the
// clock) until the next t_k, latches the true specific force and angular
// rate at t_k into the registers, in the IMU frame of the scenario's
// mounting, with the constant biases, white noise and the rolling base's
// vibration added (the register file quantises and saturates as the chip
// does), and returns the edge stamped t_k. Samples while the chip sleeps
// or has DATA_RDY_EN off raise no edge, as on the chip.
//
// Noise of sample k is counter-based (seed, axis, k): a sample's value does
// not depend on which samples were read before it. Live, the clock is the
// monotonic clock and the sleeps are real; in lockstep it is a SimClock,
// whose sleep_until() just moves time: step the driver while
// next_edge_time() <= the tick's time and no call ever sleeps.
//
// Nothing after construction allocates.
#include <cstdint>

#include "hal/clock.hpp"
#include "hal/gpio.hpp"
#include "hal/i2c_bus.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/truth_source.hpp"
#include "sim/sim_device.hpp"

namespace rtfuse::sim {

// The IMU's counterpart (sim_device.hpp): mpu.address must be the
// scenario's chip's.
std::unique_ptr<SimDevice> make_sim_imu(const SimDeviceContext& ctx, std::string* error);

// One sample before quantisation, in the IMU frame.
struct ImuChipReading {
  double accel_mps2[3] = {0.0, 0.0, 0.0};  // specific force: what an accelerometer measures
  double gyro_rad_s[3] = {0.0, 0.0, 0.0};
  double temperature_c = 0.0;
};

class SimImu final : public hal::I2cBus, public hal::GpioEdgeSource, public SimDevice {
 public:
  // `truth` and `clock` must outlive this; `truth` is read on the IMU thread.
  SimImu(const DriveScenario& scenario, TruthSource& truth, hal::Clock& clock, TimeNs t0);
  ~SimImu() override;
  SimImu(const SimImu&) = delete;
  SimImu& operator=(const SimImu&) = delete;

  // When the next sample is taken (an edge if the chip has data-ready on).
  TimeNs next_edge_time() const noexcept { return sample_time(next_); }

  // SimDevice: its I2C bus, its data-ready line, the robot's clock.
  void provide(DeviceBuses& out, hal::Clock& clock) noexcept override;
  TimeNs next_event_time() noexcept override { return next_edge_time(); }
  TimeNs sample_time(std::int64_t k) const noexcept;
  // Sample k as the chip's sensors see it, noise, vibration and bias included.
  ImuChipReading sample(std::int64_t k) const noexcept;
  // The noise-free value of the same (truth through the mounting).
  ImuChipReading ideal_sample(std::int64_t k) const noexcept;
  double gyro_noise_sigma() const noexcept { return gyro_sigma_; }
  double accel_noise_sigma() const noexcept { return accel_sigma_; }

  // Samples passed over because the reader fell further behind than the
  // kernel's edge queue holds (kEdgeQueue edges).
  static constexpr int kEdgeQueue = 16;
  std::int64_t samples_skipped() const noexcept { return skipped_; }
  std::int64_t edges() const noexcept { return edges_; }

  // nullptr when the driver set the chip up as the scenario describes it
  // (sample rate, full-scale ranges), else what differs: the edges keep the
  // scenario's rate whatever the driver wrote, so a mismatch is worth a log line.
  const char* config_mismatch() const noexcept;

  // --- faults (the fault-matrix tests drive these from the lockstep loop) -----
  // Added to every sample from now on, in the IMU frame (an impact, a
  // vibration burst); zeros end it.
  void set_disturbance(const double accel_mps2[3], const double gyro_rad_s[3]) noexcept;
  // While on, samples are latched into the registers but their data-ready
  // edges are lost (a broken interrupt wire, a GPIO misconfigured).
  void set_edges_lost(bool lost) noexcept { edges_lost_ = lost; }
  std::int64_t edges_lost() const noexcept { return lost_edges_; }

  sim::MpuRegisterFile& chip() noexcept { return chip_; }
  const sim::MpuRegisterFile& chip() const noexcept { return chip_; }
  hal::mock::MockI2cBus& bus() noexcept { return bus_; }

  // --- hal::I2cBus --------------------------------------------------------------
  hal::HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  hal::HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept override;
  std::int64_t retries() const noexcept override { return bus_.retries(); }
  // Serves both interfaces: the I2C bus's last failure (the line never fails).
  const char* last_error() const noexcept override { return bus_.last_error(); }

  // --- hal::GpioEdgeSource --------------------------------------------------------
  hal::HalStatus wait_edge(TimeNs timeout_ns, hal::GpioEdge* out) noexcept override;

 private:
  std::int64_t first_sample_at_or_after(TimeNs t) const noexcept;
  ImuChipReading reading_of(const TruthState& s) const noexcept;
  // 0..1: how much of the configured vibration the base's motion excites.
  double vibration_share(const TruthState& s) const noexcept;

  TruthSource& truth_;
  hal::Clock& clock_;
  TimeNs t0_;
  SimImuConfig cfg_;
  std::uint64_t seed_;
  double period_ns_;
  double gyro_sigma_;
  double accel_sigma_;
  double half_track_m_;
  double r_[3][3] = {};  // base_link <- IMU rotation of the mounting

  hal::mock::MockI2cBus bus_;
  sim::MpuRegisterFile chip_;
  std::int64_t next_ = 0;
  std::int64_t skipped_ = 0;
  std::int64_t edges_ = 0;
  double disturbance_accel_[3] = {};
  double disturbance_gyro_[3] = {};
  bool edges_lost_ = false;
  std::int64_t lost_edges_ = 0;
};

}  // namespace rtfuse::sim
