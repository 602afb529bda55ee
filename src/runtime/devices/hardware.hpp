#pragma once
// The devices a configuration drives, on whatever buses it is given (kernel,
// simulated robot, recording): the ones the loop polls inside its tick (the
// CANopen wheel encoders) and the ones on threads of their own (the IMU),
// behind one ThreadDevice interface. Their measurements enter the fusion
// through the same sensor rings as decoded LCM messages, so fusion semantics
// do not depend on the source.
//
// Everything is allocated in create(); before_drain(), fill_snapshot() and
// the thread devices' steps (outside a re-initialisation) allocate nothing.
#include <memory>
#include <string>

#include "runtime/devices/camera/camera_device.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/devices/gnss/gnss_device.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/devices/imu/imu_device.hpp"
#include "runtime/devices/thread_device.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoder_device.hpp"

namespace rtfuse {

constexpr int kMaxThreadDevices = 4;

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

  // The devices that want a thread (live) or lockstep steps (replay, simulation).
  int thread_device_count() const { return num_threaded_; }
  ThreadDevice& thread_device(int i) { return *threaded_[i]; }

  ImuDevice* imu() { return imu_.get(); }
  CameraDevice* camera() { return camera_.get(); }
  GnssDevice* gnss() { return gnss_.get(); }
  const drivers::CanopenEncoders* encoders() const { return wheels_ ? &wheels_->encoders() : nullptr; }
  const drivers::WheelOdometry* wheel_odometry() const { return wheels_ ? wheels_->wheel_odometry() : nullptr; }

 private:
  explicit Hardware(const RuntimeConfig& cfg);

  DeviceSlots slots_;
  DeviceStatus layout_[kMaxDevices];  // names and ids, from describe_devices
  std::unique_ptr<WheelEncoderDevice> wheels_;
  std::unique_ptr<ImuDevice> imu_;
  std::unique_ptr<CameraDevice> camera_;
  std::unique_ptr<GnssDevice> gnss_;
  ThreadDevice* threaded_[kMaxThreadDevices] = {};
  int num_threaded_ = 0;
};

}  // namespace rtfuse
