#pragma once
// What differs between an MPU-6050, MPU-6500 and MPU-9250 (identity,
// temperature formula, filter bandwidths, noise) and what they share
// (full-scale codes and sensitivities), as data from the product
// specifications and register maps.
#include <cstdint>

namespace rtfuse::drivers {

// kAuto accepts any of the three WHO_AM_I values and takes the model from it.
enum class MpuModel : std::uint8_t { kAuto, kMpu6050, kMpu6500, kMpu9250 };

const char* to_string(MpuModel m) noexcept;

namespace mpu_model {

std::uint8_t who_am_i(MpuModel m) noexcept;  // 0 for kAuto
// kAuto when the value is none of the three.
MpuModel from_who_am_i(std::uint8_t who) noexcept;
// A name for a WHO_AM_I value of a related part that is not supported
// ("MPU-9255", ...), or nullptr.
const char* other_part_name(std::uint8_t who) noexcept;

// Full-scale settings -> FS_SEL / AFS_SEL code 0..3, or -1 when not a range
// the chips have.
int gyro_fs_code(int full_scale_dps) noexcept;
int accel_fs_code(int full_scale_g) noexcept;
// LSB per deg/s: 131, 65.5, 32.8, 16.4 (the datasheet's rounded values, which
// is what the factory trim targets). LSB per g: 16384 >> code.
double gyro_lsb_per_dps(int fs_code) noexcept;
double accel_lsb_per_g(int fs_code) noexcept;

// TEMP_OUT to degrees C: raw/340 + 36.53 (6050), raw/333.87 + 21 (6500, 9250).
double temperature_c(MpuModel m, std::int16_t raw) noexcept;

// -3 dB bandwidth of the digital low-pass filter for DLPF_CFG 0..6 (6500/9250:
// the same value goes to A_DLPF_CFG, so the accel filter matches the gyro's).
double gyro_bandwidth_hz(MpuModel m, int dlpf) noexcept;
double accel_bandwidth_hz(MpuModel m, int dlpf) noexcept;
// Sample rate: the gyro output rate (8 kHz with DLPF_CFG 0, else 1 kHz)
// divided by 1 + SMPLRT_DIV.
double sample_rate_hz(int dlpf, int smplrt_div) noexcept;

// Typical noise spectral densities from the product specifications:
// gyro 0.005 deg/s/sqrt(Hz) (6050), 0.01 (6500, 9250); accel 400 ug/sqrt(Hz)
// (6050), 300 (6500, 9250). In SI: rad/s/sqrt(Hz) and m/s^2/sqrt(Hz).
double gyro_noise_density(MpuModel m) noexcept;
double accel_noise_density(MpuModel m) noexcept;

}  // namespace mpu_model
}  // namespace rtfuse::drivers
