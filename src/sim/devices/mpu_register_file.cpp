#include "sim/devices/mpu_register_file.hpp"

#include <cmath>

#include "core/physical_constants.hpp"

namespace rtfuse::sim {

namespace mpu {

std::uint8_t who_am_i(MpuChip model) noexcept {
  switch (model) {
    case MpuChip::kMpu6050: return 0x68;
    case MpuChip::kMpu6500: return 0x70;
    case MpuChip::kMpu9250: return 0x71;
  }
  return 0x68;
}

std::uint8_t pwr_mgmt_1_reset_value(MpuChip model) noexcept {
  return model == MpuChip::kMpu6050 ? kPwrSleep : std::uint8_t{0x01};
}

double accel_lsb_per_g(int afs_sel) noexcept {
  static constexpr double kLsb[4] = {16384.0, 8192.0, 4096.0, 2048.0};
  return kLsb[afs_sel & 3];
}

double gyro_lsb_per_dps(int fs_sel) noexcept {
  static constexpr double kLsb[4] = {131.0, 65.5, 32.8, 16.4};
  return kLsb[fs_sel & 3];
}

double temperature_c(MpuChip model, std::int16_t raw) noexcept {
  return model == MpuChip::kMpu6050 ? raw / 340.0 + 36.53 : raw / 333.87 + 21.0;
}

}  // namespace mpu

namespace {

constexpr double kPi = 3.14159265358979323846;

// The chip's output clips; the +-32767 bound keeps positive and negative
// full scale symmetric, so a saturated axis reads the same magnitude both ways.
std::int16_t to_raw(double lsb) noexcept {
  if (lsb >= 32767.0) return 32767;
  if (lsb <= -32767.0) return -32767;
  return static_cast<std::int16_t>(std::lround(lsb));
}

// Sensor output, status and external sensor data, and identity: the host can
// read them, writes are acknowledged and ignored as the chip does.
bool read_only(std::uint8_t reg) noexcept { return (reg >= mpu::kIntStatus && reg <= 0x60) || reg == mpu::kWhoAmI; }

}  // namespace

MpuRegisterFile::MpuRegisterFile(MpuChip model) noexcept : model_(model) { reset_registers(); }

void MpuRegisterFile::reset_registers() noexcept {
  for (auto& r : regs_) r = 0;
  regs_[mpu::kPwrMgmt1] = mpu::pwr_mgmt_1_reset_value(model_);
  regs_[mpu::kWhoAmI] = who_am_i_override_ ? who_am_i_value_ : mpu::who_am_i(model_);
}

void MpuRegisterFile::set_wrong_who_am_i(std::uint8_t value) noexcept {
  who_am_i_override_ = true;
  who_am_i_value_ = value;
  regs_[mpu::kWhoAmI] = value;
}

void MpuRegisterFile::clear_faults() noexcept {
  nack_remaining_ = 0;
  frozen_ = false;
  who_am_i_override_ = false;
  regs_[mpu::kWhoAmI] = mpu::who_am_i(model_);
}

std::int16_t MpuRegisterFile::peek16(std::uint8_t reg_h) const noexcept {
  const auto hi = static_cast<std::uint16_t>(regs_[reg_h]);
  const auto lo = static_cast<std::uint16_t>(regs_[static_cast<std::uint8_t>(reg_h + 1)]);
  return static_cast<std::int16_t>(static_cast<std::uint16_t>((hi << 8) | lo));
}

double MpuRegisterFile::sample_rate_hz() const noexcept {
  const int dlpf = regs_[mpu::kConfig] & 7;
  const double gyro_rate = (dlpf == 0 || dlpf == 7) ? 8000.0 : 1000.0;
  return gyro_rate / (1.0 + regs_[mpu::kSmplrtDiv]);
}

void MpuRegisterFile::latch(const std::int16_t accel[3], std::int16_t temp, const std::int16_t gyro[3]) noexcept {
  auto put = [this](std::uint8_t reg, std::int16_t v) {
    const auto u = static_cast<std::uint16_t>(v);
    regs_[reg] = static_cast<std::uint8_t>(u >> 8);
    regs_[reg + 1] = static_cast<std::uint8_t>(u & 0xFF);
  };
  for (int i = 0; i < 3; ++i) put(static_cast<std::uint8_t>(mpu::kAccelXoutH + 2 * i), accel[i]);
  put(mpu::kTempOutH, temp);
  for (int i = 0; i < 3; ++i) put(static_cast<std::uint8_t>(mpu::kGyroXoutH + 2 * i), gyro[i]);
}

bool MpuRegisterFile::raise_data_ready() noexcept {
  if ((regs_[mpu::kIntEnable] & mpu::kDataRdyEn) == 0) return false;
  regs_[mpu::kIntStatus] |= mpu::kDataRdyInt;
  return true;
}

bool MpuRegisterFile::set_raw_sample(const std::int16_t accel[3], std::int16_t temp,
                                     const std::int16_t gyro[3]) noexcept {
  if (asleep()) return false;
  if (!frozen_) latch(accel, temp, gyro);
  return raise_data_ready();
}

bool MpuRegisterFile::set_sample(const double accel_mps2[3], const double gyro_rad_s[3], double temp_c) noexcept {
  if (!std::isfinite(temp_c)) return false;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(accel_mps2[i]) || !std::isfinite(gyro_rad_s[i])) return false;
  }
  const double a_scale = mpu::accel_lsb_per_g(accel_fs_sel()) / kStandardGravity;
  const double g_scale = mpu::gyro_lsb_per_dps(gyro_fs_sel()) * 180.0 / kPi;
  std::int16_t a[3];
  std::int16_t g[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = to_raw(accel_mps2[i] * a_scale);
    g[i] = to_raw(gyro_rad_s[i] * g_scale);
  }
  const std::int16_t t =
      model_ == MpuChip::kMpu6050 ? to_raw((temp_c - 36.53) * 340.0) : to_raw((temp_c - 21.0) * 333.87);
  return set_raw_sample(a, t, g);
}

hal::HalStatus MpuRegisterFile::i2c_read(std::uint8_t reg, std::uint8_t* buf, int n) noexcept {
  if (nack_remaining_ > 0) {
    --nack_remaining_;
    return hal::HalStatus::kNack;
  }
  if (buf == nullptr || n < 1) return hal::HalStatus::kIoError;
  bool read_status = false;
  for (int i = 0; i < n; ++i) {
    const auto r = static_cast<std::uint8_t>(reg + i);
    buf[i] = regs_[r];
    read_status = read_status || r == mpu::kIntStatus;
  }
  if (read_status || (regs_[mpu::kIntPinCfg] & mpu::kIntRdClear) != 0) regs_[mpu::kIntStatus] = 0;
  return hal::HalStatus::kOk;
}

hal::HalStatus MpuRegisterFile::i2c_write(std::uint8_t reg, std::uint8_t value) noexcept {
  if (nack_remaining_ > 0) {
    --nack_remaining_;
    return hal::HalStatus::kNack;
  }
  if (reg == mpu::kPwrMgmt1 && (value & mpu::kPwrDeviceReset) != 0) {
    reset_registers();
    ++reset_count_;
    return hal::HalStatus::kOk;
  }
  if (!read_only(reg)) regs_[reg] = value;
  return hal::HalStatus::kOk;
}

}  // namespace rtfuse::sim
