#include "drivers/imu/mpu_noise.hpp"

#include <cmath>

namespace rtfuse::drivers {

namespace {
bool positive(double v) noexcept { return std::isfinite(v) && v > 0.0; }
}  // namespace

MpuNoise mpu_noise(const MpuNoiseConfig& config, MpuModel model, int dlpf, double gyro_lsb_rad_s,
                   double accel_lsb_mps2) noexcept {
  const double gyro_density =
      positive(config.gyro_noise_density) ? config.gyro_noise_density : mpu_model::gyro_noise_density(model);
  const double accel_density =
      positive(config.accel_noise_density) ? config.accel_noise_density : mpu_model::accel_noise_density(model);
  MpuNoise n;
  n.gyro_noise_density = gyro_density;
  n.gyro_variance = positive(config.gyro_variance)
                        ? config.gyro_variance
                        : gyro_density * gyro_density * mpu_model::gyro_bandwidth_hz(model, dlpf) +
                              gyro_lsb_rad_s * gyro_lsb_rad_s / 12.0;
  n.accel_variance = positive(config.accel_variance)
                         ? config.accel_variance
                         : accel_density * accel_density * mpu_model::accel_bandwidth_hz(model, dlpf) +
                               accel_lsb_mps2 * accel_lsb_mps2 / 12.0;
  return n;
}

}  // namespace rtfuse::drivers
