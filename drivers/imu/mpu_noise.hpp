#pragma once
// Measurement noise of an MPU sample, per axis.
//
// Default: the datasheet noise density times the square root of the DLPF's
// -3 dB bandwidth (variance = N^2 B), plus the quantisation step's LSB^2/12.
// The datasheet itself relates its numbers this way: the 6050's 0.005
// deg/s/sqrt(Hz) over the 98 Hz filter is its 0.05 deg/s-rms total noise.
// A configured variance (> 0) replaces the model, e.g. one measured at rest.
#include "drivers/imu/mpu_model.hpp"

namespace rtfuse::drivers {

struct MpuNoiseConfig {
  double gyro_noise_density = 0.0;   // rad/s/sqrt(Hz); <= 0: the model's datasheet value
  double accel_noise_density = 0.0;  // m/s^2/sqrt(Hz); <= 0: the model's datasheet value
  double gyro_variance = 0.0;        // (rad/s)^2 per sample; > 0 replaces the density model
  double accel_variance = 0.0;       // (m/s^2)^2 per sample; > 0 replaces the density model
};

struct MpuNoise {
  double gyro_noise_density = 0.0;  // rad/s/sqrt(Hz): the attitude filter's angle random walk
  double gyro_variance = 0.0;       // (rad/s)^2
  double accel_variance = 0.0;      // (m/s^2)^2
};

// model: the detected one (not kAuto); dlpf 0..6; lsb: the scale of one count.
MpuNoise mpu_noise(const MpuNoiseConfig& config, MpuModel model, int dlpf, double gyro_lsb_rad_s,
                   double accel_lsb_mps2) noexcept;

}  // namespace rtfuse::drivers
