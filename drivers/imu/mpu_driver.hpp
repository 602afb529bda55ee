#pragma once
// Register-level driver for an InvenSense MPU-6050 / MPU-6500 / MPU-9250 on
// one I2C bus: identity check, reset and configuration with read-back, and
// one 14-byte burst read per sample, scaled to SI and rotated into base_link.
//
// Interrupt pin: INT_PIN_CFG = INT_RD_CLEAR with the latch off. The pin gives
// a 50 us pulse per sample whether or not the previous one was read, so a
// missed read never stalls the data-ready line (a latched pin would stay high
// and produce no further rising edge), and the burst data read clears
// INT_STATUS without a second transfer. Request rising edges on the line.
//
// Saturation: a raw value at 32767 or at -32767/-32768 is flagged. The
// datasheet range is -32768..32767, but InvenSense parts (and the mock) clip
// symmetrically at -32767, so both negative codes mean "at full scale".
//
// init() may sleep (100 ms after DEVICE_RESET) and is for start-up and
// recovery, not the loop thread; read() never allocates or blocks beyond the
// bus transfer.
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/time.hpp"
#include "drivers/imu/error_text.hpp"
#include "drivers/imu/mpu_model.hpp"
#include "hal/clock.hpp"
#include "hal/i2c_bus.hpp"
#include "hal/status.hpp"

namespace rtfuse::drivers {

enum class MpuSaturation : std::uint8_t {
  kFlag,    // the sample is delivered with the saturated quantity flagged
  kReject,  // the whole sample is dropped (MpuReadStatus::kSaturated); not a chip fault
};

struct MpuConfig {
  std::uint8_t address = 0x68;  // 0x68 (AD0 low) or 0x69 (AD0 high)
  MpuModel model = MpuModel::kAuto;
  int sample_rate_div = 9;  // SMPLRT_DIV 0..255: 1 kHz / (1 + div) with the DLPF on (100 Hz here)
  int dlpf = 3;             // DLPF_CFG 0..6; 3 = 44 Hz accel / 42 Hz gyro (6050)
  int gyro_full_scale_dps = 500;  // 250, 500, 1000, 2000
  int accel_full_scale_g = 4;     // 2, 4, 8, 16
  // Rotation of the chip's axes into base_link: v_base = base_R_imu * v_imu.
  Eigen::Quaterniond base_R_imu = Eigen::Quaterniond::Identity();
  // The same 14 data bytes this many reads in a row = a frozen signal chain.
  // Real sensor noise never repeats 14 bytes; 0 disables (a noiseless simulator).
  int frozen_reads = 5;
  // Consecutive failed reads (bus errors, frozen, impossible) before
  // needs_reinit() says the chip should be initialised again.
  int failures_before_reinit = 5;
  MpuSaturation saturation = MpuSaturation::kFlag;
};

enum class MpuReadStatus : std::uint8_t {
  kOk,
  kSaturated,   // MpuSaturation::kReject and a saturated axis: sample dropped
  kNack,
  kBusError,
  kTimeout,
  kIoError,     // any other bus failure (closed, malformed, I/O)
  kFrozen,
  kImpossible,  // all-zero / all-0xFF bytes or a temperature outside -40..85 C
  kNotInitialised,
};

const char* to_string(MpuReadStatus s) noexcept;

struct ImuReading {
  TimeNs stamp = 0;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // m/s^2 in base_link, gravity included (specific force)
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // rad/s in base_link
  double temperature_c = 0.0;
  // Any chip axis at full scale: after the rotation every base_link axis may
  // contain it, so the whole vector is flagged.
  bool accel_saturated = false;
  bool gyro_saturated = false;
  std::int16_t raw[7] = {};  // as read: accel xyz, temp, gyro xyz (chip axes)
};

struct MpuDriverStats {
  std::int64_t inits = 0;          // successful init() calls
  std::int64_t init_failures = 0;
  std::int64_t reads = 0;          // read() calls
  std::int64_t good_reads = 0;     // kOk
  std::int64_t nacks = 0;
  std::int64_t bus_errors = 0;
  std::int64_t timeouts = 0;
  std::int64_t io_errors = 0;
  std::int64_t frozen = 0;
  std::int64_t saturated = 0;      // samples with any axis at full scale
  std::int64_t impossible = 0;
  std::int64_t reinit_requests = 0;  // times needs_reinit() turned true
  int consecutive_failures = 0;
};

class MpuDriver {
 public:
  MpuDriver(hal::I2cBus& bus, hal::Clock& clock, const MpuConfig& config) noexcept;

  // Identity, reset, configuration and read-back. On false, error() says what
  // failed, the value seen, what was expected and the likely cause.
  bool init(TimeNs now) noexcept;

  // One burst read, stamped with `stamp` (the data-ready edge's kernel time,
  // or the clock at read time without a line). *out is written on kOk only.
  MpuReadStatus read(TimeNs stamp, ImuReading* out) noexcept;

  bool initialised() const noexcept { return initialised_; }
  // K consecutive failed reads: call init() again (cleared by a good read or init).
  bool needs_reinit() const noexcept { return needs_reinit_; }
  const char* error() const noexcept { return error_.c_str(); }

  // The model found by init() (the configured one, or the one WHO_AM_I named under kAuto).
  MpuModel model() const noexcept { return model_; }
  double sample_rate_hz() const noexcept;
  TimeNs sample_period_ns() const noexcept;
  double gyro_full_scale_rad_s() const noexcept { return gyro_scale_ * 32767.0; }
  double accel_full_scale_mps2() const noexcept { return accel_scale_ * 32767.0; }
  double gyro_lsb_rad_s() const noexcept { return gyro_scale_; }
  double accel_lsb_mps2() const noexcept { return accel_scale_; }
  const Eigen::Matrix3d& base_R_imu() const noexcept { return base_R_imu_; }
  const MpuConfig& config() const noexcept { return config_; }
  const MpuDriverStats& stats() const noexcept { return stats_; }

 private:
  bool check_config() noexcept;
  bool check_identity() noexcept;
  bool reset_chip(TimeNs now) noexcept;
  bool write(std::uint8_t reg, std::uint8_t value, const char* name) noexcept;
  bool configure() noexcept;
  bool verify(std::uint8_t reg, std::uint8_t expected, std::uint8_t actual, const char* name) noexcept;
  MpuReadStatus fail(MpuReadStatus s) noexcept;
  MpuReadStatus bus_failure(hal::HalStatus s) noexcept;

  hal::I2cBus& bus_;
  hal::Clock& clock_;
  MpuConfig config_;
  MpuModel model_;
  Eigen::Matrix3d base_R_imu_ = Eigen::Matrix3d::Identity();
  double accel_scale_ = 0.0;  // m/s^2 per LSB
  double gyro_scale_ = 0.0;   // rad/s per LSB
  std::uint8_t gyro_config_ = 0;
  std::uint8_t accel_config_ = 0;
  bool initialised_ = false;
  bool needs_reinit_ = false;
  std::uint8_t last_bytes_[14] = {};
  int same_count_ = 0;
  MpuDriverStats stats_;
  ErrorText error_;
};

}  // namespace rtfuse::drivers
