#pragma once
// [mpu] and [mpu.attitude]: an InvenSense MPU-6050/6500/9250 on I2C with an
// optional data-ready line, as the TOML describes it. Plain values;
// imu_device.cpp turns them into the driver's config.
// Schema: docs/configuration.md.
#include <cstdint>

#include "runtime/config/name.hpp"

namespace rtfuse {

enum class MpuModelConfig : std::uint8_t { kAuto, kMpu6050, kMpu6500, kMpu9250 };
enum class AttitudeAlgorithmConfig : std::uint8_t { kMadgwick, kMahony };

struct AttitudeSection {
  AttitudeAlgorithmConfig algorithm = AttitudeAlgorithmConfig::kMadgwick;
  double beta = 0.1;    // Madgwick gain
  double zeta = 0.005;  // Madgwick gyro-bias gain
  double kp = 1.0;      // Mahony proportional gain
  double ki = 0.02;     // Mahony integral gain (gyro bias)
  // The driver's gyro bias learner at IMU-only stillness
  // (drivers/imu/stillness_bias.hpp). Off for a base smooth enough that a
  // slow steady turn passes its test; the wheels' standstills then teach
  // the bias instead ([[sensor]] standstill_from).
  bool stillness_bias = true;
};

struct MpuSection {
  bool enabled = false;
  Name device{"/dev/i2c-1"};
  std::uint8_t address = 0x68;
  MpuModelConfig model = MpuModelConfig::kAuto;
  int sample_rate_divider = 4;  // 1 kHz / (1 + 4) = 200 Hz with the DLPF on
  int dlpf = 3;
  int gyro_range_dps = 500;
  int accel_range_g = 4;
  Name data_ready_chip;         // gpiochip label or path; "" = no line, poll
  int data_ready_line = -1;
  double poll_rate_hz = 200.0;  // without a data-ready line
  Name frame{"imu_link"};       // mounting: static transform base_link -> frame
  int frozen_reads = 10;
  double gyro_noise_rad_s = 0.005;   // per-sample 1-sigma
  double accel_noise_mps2 = 0.05;
  AttitudeSection attitude;
};

}  // namespace rtfuse
