#pragma once
// The register map of an InvenSense MPU-6050 / MPU-6500 / MPU-9250 (the
// accel/gyro part they share), as much of it as an IMU driver touches, with
// the chip's behaviour where a driver depends on it:
//
//  - WHO_AM_I (0x75): 0x68 (6050), 0x70 (6500), 0x71 (9250); read-only.
//  - PWR_MGMT_1 (0x6B): DEVICE_RESET (bit 7) restores every register to its
//    reset value and clears itself. Reset values per the register maps: 0x40
//    (SLEEP) on the 6050, 0x01 (awake, CLKSEL=1) on the 6500 and 9250. While
//    SLEEP (bit 6) is set the sensors do not sample.
//  - SMPLRT_DIV 0x19, CONFIG 0x1A (DLPF_CFG bits 2:0), GYRO_CONFIG 0x1B
//    (FS_SEL bits 4:3), ACCEL_CONFIG 0x1C (AFS_SEL bits 4:3): plain storage,
//    except that the full-scale fields set the scaling of the next sample.
//  - INT_PIN_CFG 0x37 (INT_RD_CLEAR bit 4), INT_ENABLE 0x38 (DATA_RDY_EN bit
//    0), INT_STATUS 0x3A (DATA_RDY_INT bit 0, set by a new sample when enabled,
//    cleared by reading INT_STATUS, or by any read when INT_RD_CLEAR is set).
//  - ACCEL_XOUT_H 0x3B .. GYRO_ZOUT_L 0x48: big-endian signed 16-bit, in the
//    order accel x y z, temperature, gyro x y z; read-only.
// Reads auto-increment the register pointer, as a burst read relies on.
#include <cstdint>

#include "hal/mock/mock_i2c_bus.hpp"
#include "core/physical_constants.hpp"

namespace rtfuse::sim {

enum class MpuChip : std::uint8_t { kMpu6050, kMpu6500, kMpu9250 };

namespace mpu {
constexpr std::uint8_t kSmplrtDiv = 0x19;
constexpr std::uint8_t kConfig = 0x1A;
constexpr std::uint8_t kGyroConfig = 0x1B;
constexpr std::uint8_t kAccelConfig = 0x1C;
constexpr std::uint8_t kIntPinCfg = 0x37;
constexpr std::uint8_t kIntEnable = 0x38;
constexpr std::uint8_t kIntStatus = 0x3A;
constexpr std::uint8_t kAccelXoutH = 0x3B;
constexpr std::uint8_t kTempOutH = 0x41;
constexpr std::uint8_t kGyroXoutH = 0x43;
constexpr std::uint8_t kGyroZoutL = 0x48;
constexpr std::uint8_t kPwrMgmt1 = 0x6B;
constexpr std::uint8_t kWhoAmI = 0x75;

constexpr std::uint8_t kPwrDeviceReset = 0x80;
constexpr std::uint8_t kPwrSleep = 0x40;
constexpr std::uint8_t kIntRdClear = 0x10;
constexpr std::uint8_t kDataRdyEn = 0x01;
constexpr std::uint8_t kDataRdyInt = 0x01;

std::uint8_t who_am_i(MpuChip model) noexcept;
std::uint8_t pwr_mgmt_1_reset_value(MpuChip model) noexcept;
// LSB per g for AFS_SEL 0..3: 16384, 8192, 4096, 2048.
double accel_lsb_per_g(int afs_sel) noexcept;
// LSB per deg/s for FS_SEL 0..3: 131, 65.5, 32.8, 16.4.
double gyro_lsb_per_dps(int fs_sel) noexcept;
// Raw TEMP_OUT -> degrees C: raw/340 + 36.53 (6050), raw/333.87 + 21 (6500, 9250).
double temperature_c(MpuChip model, std::int16_t raw) noexcept;
}  // namespace mpu

class MpuRegisterFile final : public hal::mock::I2cDevice {
 public:
  explicit MpuRegisterFile(MpuChip model) noexcept;

  MpuChip model() const noexcept { return model_; }

  // --- the physical side -----------------------------------------------------
  // A new sample, converted with the current full-scale ranges, rounded to
  // the nearest LSB and saturated at +-32767 as the chip's output does.
  // Returns true when the sample raised DATA_RDY_INT (INT_ENABLE.DATA_RDY_EN
  // set): the moment a simulation should put an edge on the data-ready line.
  // Nothing happens while asleep or when an input is not finite. A frozen
  // chip keeps raising data-ready but its data registers keep the old values.
  bool set_sample(const double accel_mps2[3], const double gyro_rad_s[3], double temp_c) noexcept;
  // The same with raw register values, for replaying recorded bytes.
  bool set_raw_sample(const std::int16_t accel[3], std::int16_t temp, const std::int16_t gyro[3]) noexcept;

  // Register contents without the side effects of a bus read.
  std::uint8_t peek(std::uint8_t reg) const noexcept { return regs_[reg]; }
  std::int16_t peek16(std::uint8_t reg_h) const noexcept;
  bool asleep() const noexcept { return (regs_[mpu::kPwrMgmt1] & mpu::kPwrSleep) != 0; }
  int accel_fs_sel() const noexcept { return (regs_[mpu::kAccelConfig] >> 3) & 3; }
  int gyro_fs_sel() const noexcept { return (regs_[mpu::kGyroConfig] >> 3) & 3; }
  // Level of the INT pin's source: a data-ready interrupt is pending.
  bool data_ready_pending() const noexcept { return (regs_[mpu::kIntStatus] & mpu::kDataRdyInt) != 0; }
  // Sample rate from SMPLRT_DIV and DLPF_CFG: 8 kHz gyro output rate with the
  // DLPF off (0 or 7), else 1 kHz, divided by 1 + SMPLRT_DIV.
  double sample_rate_hz() const noexcept;
  int reset_count() const noexcept { return reset_count_; }

  // --- faults ------------------------------------------------------------------
  // The next n transfers (attempts) are not acknowledged; nothing changes.
  void nack_next(int n) noexcept { nack_remaining_ = n > 0 ? n : 0; }
  int nacks_pending() const noexcept { return nack_remaining_; }
  // Frozen: data registers stop updating (a hung signal chain).
  void set_frozen(bool frozen) noexcept { frozen_ = frozen; }
  // A different part (or a counterfeit) at the address: WHO_AM_I reads
  // `value`, and keeps doing so across resets.
  void set_wrong_who_am_i(std::uint8_t value) noexcept;
  void clear_faults() noexcept;

  // --- hal::mock::I2cDevice ------------------------------------------------------------
  hal::HalStatus i2c_read(std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  hal::HalStatus i2c_write(std::uint8_t reg, std::uint8_t value) noexcept override;

 private:
  void reset_registers() noexcept;
  void latch(const std::int16_t accel[3], std::int16_t temp, const std::int16_t gyro[3]) noexcept;
  bool raise_data_ready() noexcept;

  MpuChip model_;
  std::uint8_t regs_[256] = {};
  int reset_count_ = 0;
  int nack_remaining_ = 0;
  bool frozen_ = false;
  bool who_am_i_override_ = false;
  std::uint8_t who_am_i_value_ = 0;
};

}  // namespace rtfuse::sim
