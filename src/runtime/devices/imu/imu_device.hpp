#pragma once
// The MPU IMU as a thread device: each step waits for one data-ready edge (or
// the next poll), reads the chip, filters attitude and pushes one sample into
// the IMU sensor's ring; its health crosses to the loop through a SeqLatch.
#include <atomic>
#include <memory>
#include <string>

#include "core/seq_cell.hpp"
#include "drivers/imu/mpu_imu.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/device_buses.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

// base_R_imu comes from the frame tree: the static transform base_link -> mpu.frame.
bool imu_driver_config(const RuntimeConfig& cfg, const geometry::FrameTree& frames, drivers::MpuImuConfig* out,
                       std::string* error);

extern const char* const kImuKeys[13];

class ImuDevice final : public Device {
 public:
  // The configuration is the core's; buses.i2c and buses.clock are required,
  // buses.edge is the data-ready line (null: poll).
  static std::unique_ptr<ImuDevice> create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                           std::string* error);

  // Before the threads: identity check and configuration of the chip.
  bool start(TimeNs now, std::string* error) override;
  void step(TimeNs timeout_ns) noexcept override { step_imu(timeout_ns); }
  int sensor() const noexcept override { return sensor_; }
  std::int64_t samples() const noexcept override { return samples_.load(std::memory_order_acquire); }
  void fill_snapshot(Snapshot& s) noexcept override;

  // One step with the driver's verdict (tests look at it).
  drivers::StepResult step_imu(TimeNs timeout_ns) noexcept;

 private:
  ImuDevice(FusionCore& core, int device_slot);

  // What the IMU thread shares with the loop.
  struct Health {
    drivers::MpuImuStats stats;
    drivers::StepResult last = drivers::StepResult::kDown;
    double temperature_c = 0.0;
    std::int64_t last_sample_ns = 0;
    // The driver's last error, kept after a successful re-initialisation
    // (which clears the driver's own text).
    DeviceMessage error;
  };

  FusionCore& core_;
  int sensor_ = -1;
  int slot_ = -1;
  std::unique_ptr<drivers::MpuImu> imu_;
  est::SensorSample sample_;
  drivers::ImuMeasurement measurement_;
  Health scratch_;
  SeqLatch<Health> health_;
  std::atomic<std::int64_t> samples_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
