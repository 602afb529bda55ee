#pragma once
// The drivers a configuration runs, on whatever buses it is given (kernel,
// simulated robot, recording): the CANopen encoders and wheel odometry,
// polled by the loop inside its tick, and the MPU IMU, stepped by its own
// thread. Their measurements enter the fusion through the same sensor rings
// as decoded LCM messages, so fusion semantics do not depend on the source.
//
// Everything is allocated in create(); before_drain(), fill_snapshot() and
// imu_step() (outside a chip re-initialisation) allocate nothing.
#include <atomic>
#include <memory>
#include <string>

#include "core/seqlock.hpp"
#include "drivers/canopen/canopen_encoders.hpp"
#include "drivers/imu/mpu_imu.hpp"
#include "drivers/wheel/wheel_odometry.hpp"
#include "runtime/device_layout.hpp"
#include "runtime/fusion_core.hpp"
#include "runtime/hal_buses.hpp"

namespace rtfuse {

// Driver configs from the TOML's plain values (also used by tools that
// build the drivers themselves).
drivers::CanopenEncodersConfig encoder_driver_config(const RuntimeConfig& cfg);
drivers::WheelOdometryConfig wheel_driver_config(const RuntimeConfig& cfg);
// base_R_imu comes from the frame tree: the static transform base_link -> mpu.frame.
bool imu_driver_config(const RuntimeConfig& cfg, const geometry::FrameTree& frames, drivers::MpuImuConfig* out,
                       std::string* error);

class Hardware final : public TickDevices {
 public:
  // The configuration is the core's.
  static std::unique_ptr<Hardware> create(const HalBuses& buses, FusionCore& core, std::string* error);

  // Before the threads: NMT start to the encoder nodes, IMU identity check
  // and configuration. False with *error naming the device and the fix.
  bool start(TimeNs now, std::string* error);

  // Loop thread (TickDevices).
  void before_drain(TimeNs now) noexcept override;
  void fill_snapshot(Snapshot& s) noexcept override;

  // IMU thread: wait for one data-ready edge (or the next poll), read, filter,
  // push into the IMU sensor's ring.
  bool has_imu() const { return imu_ != nullptr; }
  drivers::StepResult imu_step(TimeNs edge_timeout_ns) noexcept;
  // Samples pushed into the IMU sensor's ring so far (IMU thread's count).
  std::int64_t imu_samples() const { return imu_samples_.load(std::memory_order_acquire); }

  const drivers::CanopenEncoders* encoders() const { return encoders_.get(); }
  const drivers::WheelOdometry* wheel_odometry() const { return wheels_.get(); }

 private:
  explicit Hardware(const RuntimeConfig& cfg, FusionCore& core);
  void fill_can(Snapshot& s) noexcept;
  void fill_imu(Snapshot& s) noexcept;

  // What the IMU thread shares with the loop, through a seqlock.
  struct ImuHealth {
    drivers::MpuImuStats stats;
    drivers::StepResult last = drivers::StepResult::kDown;
    double temperature_c = 0.0;
    std::int64_t last_sample_ns = 0;
  };

  const RuntimeConfig& cfg_;
  FusionCore& core_;
  DeviceSlots slots_;
  DeviceStatus layout_[kMaxDevices];  // names and ids, from describe_devices
  int base_frame_ = -1;
  std::unique_ptr<drivers::CanopenEncoders> encoders_;
  std::unique_ptr<drivers::WheelOdometry> wheels_;
  std::unique_ptr<drivers::MpuImu> imu_;
  drivers::WheelTwist last_twist_;
  bool have_twist_ = false;
  est::SensorSample wheel_sample_;
  est::SensorSample imu_sample_;
  drivers::ImuMeasurement imu_measurement_;
  ImuHealth imu_health_scratch_;
  SeqLock<ImuHealth> imu_health_;
  std::atomic<std::int64_t> imu_samples_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
