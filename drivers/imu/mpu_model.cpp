#include "drivers/imu/mpu_model.hpp"

#include "drivers/imu/mpu_registers.hpp"
#include "core/physical_constants.hpp"

namespace rtfuse::drivers {

namespace {

int clamp_dlpf(int dlpf) noexcept { return dlpf < 0 ? 0 : (dlpf > 6 ? 6 : dlpf); }
}  // namespace

const char* to_string(MpuModel m) noexcept {
  switch (m) {
    case MpuModel::kAuto: return "auto";
    case MpuModel::kMpu6050: return "MPU-6050";
    case MpuModel::kMpu6500: return "MPU-6500";
    case MpuModel::kMpu9250: return "MPU-9250";
  }
  return "?";
}

namespace mpu_model {

std::uint8_t who_am_i(MpuModel m) noexcept {
  switch (m) {
    case MpuModel::kMpu6050: return mpu_reg::kWhoAmI6050;
    case MpuModel::kMpu6500: return mpu_reg::kWhoAmI6500;
    case MpuModel::kMpu9250: return mpu_reg::kWhoAmI9250;
    case MpuModel::kAuto: break;
  }
  return 0;
}

MpuModel from_who_am_i(std::uint8_t who) noexcept {
  switch (who) {
    case mpu_reg::kWhoAmI6050: return MpuModel::kMpu6050;
    case mpu_reg::kWhoAmI6500: return MpuModel::kMpu6500;
    case mpu_reg::kWhoAmI9250: return MpuModel::kMpu9250;
    default: return MpuModel::kAuto;
  }
}

const char* other_part_name(std::uint8_t who) noexcept {
  switch (who) {
    case mpu_reg::kWhoAmI9255: return "MPU-9255";
    case mpu_reg::kWhoAmIIcm20602: return "ICM-20602";
    case mpu_reg::kWhoAmIIcm20689: return "ICM-20689";
    default: return nullptr;
  }
}

int gyro_fs_code(int full_scale_dps) noexcept {
  switch (full_scale_dps) {
    case 250: return 0;
    case 500: return 1;
    case 1000: return 2;
    case 2000: return 3;
    default: return -1;
  }
}

int accel_fs_code(int full_scale_g) noexcept {
  switch (full_scale_g) {
    case 2: return 0;
    case 4: return 1;
    case 8: return 2;
    case 16: return 3;
    default: return -1;
  }
}

double gyro_lsb_per_dps(int fs_code) noexcept {
  static constexpr double kLsb[4] = {131.0, 65.5, 32.8, 16.4};
  return kLsb[fs_code & 3];
}

double accel_lsb_per_g(int fs_code) noexcept { return static_cast<double>(16384 >> (fs_code & 3)); }

double temperature_c(MpuModel m, std::int16_t raw) noexcept {
  return m == MpuModel::kMpu6050 ? raw / 340.0 + 36.53 : raw / 333.87 + 21.0;
}

double gyro_bandwidth_hz(MpuModel m, int dlpf) noexcept {
  static constexpr double k6050[7] = {256.0, 188.0, 98.0, 42.0, 20.0, 10.0, 5.0};
  static constexpr double k6500[7] = {250.0, 184.0, 92.0, 41.0, 20.0, 10.0, 5.0};
  return m == MpuModel::kMpu6050 ? k6050[clamp_dlpf(dlpf)] : k6500[clamp_dlpf(dlpf)];
}

double accel_bandwidth_hz(MpuModel m, int dlpf) noexcept {
  static constexpr double k6050[7] = {260.0, 184.0, 94.0, 44.0, 21.0, 10.0, 5.0};
  static constexpr double k6500[7] = {218.1, 218.1, 99.0, 44.8, 21.2, 10.2, 5.05};
  return m == MpuModel::kMpu6050 ? k6050[clamp_dlpf(dlpf)] : k6500[clamp_dlpf(dlpf)];
}

double sample_rate_hz(int dlpf, int smplrt_div) noexcept {
  const double gyro_rate = dlpf == 0 ? 8000.0 : 1000.0;
  return gyro_rate / (1.0 + smplrt_div);
}

double gyro_noise_density(MpuModel m) noexcept {
  const double dps = m == MpuModel::kMpu6050 ? 0.005 : 0.01;
  return dps * kPi / 180.0;
}

double accel_noise_density(MpuModel m) noexcept {
  const double ug = m == MpuModel::kMpu6050 ? 400.0 : 300.0;
  return ug * 1e-6 * kStandardGravity;
}

}  // namespace mpu_model
}  // namespace rtfuse::drivers
