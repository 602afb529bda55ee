#pragma once
// The CANopen wheel encoders and the wheel odometry they feed, polled by the
// loop inside its tick: SYNC out, TPDOs in, one twist per complete set of
// positions into the wheel sensor's ring before the drain.
#include <memory>
#include <string>

#include "drivers/canopen/canopen_encoders.hpp"
#include "drivers/wheel/wheel_odometry.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

// Driver configs from the TOML's plain values (also used by tools that
// build the drivers themselves).
drivers::CanopenEncodersConfig encoder_driver_config(const RuntimeConfig& cfg);
drivers::WheelOdometryConfig wheel_driver_config(const RuntimeConfig& cfg);

class WheelEncoderDevice {
 public:
  // The configuration is the core's.
  static std::unique_ptr<WheelEncoderDevice> create(hal::CanBus& bus, FusionCore& core, const DeviceSlots& slots,
                                                    std::string* error);
  // NMT start to the encoder nodes.
  bool start(TimeNs now, std::string* error);
  // Loop thread.
  void before_drain(TimeNs now) noexcept;
  void fill_snapshot(Snapshot& s) noexcept;

  const drivers::CanopenEncoders& encoders() const { return *encoders_; }
  const drivers::WheelOdometry* wheel_odometry() const { return wheels_.get(); }

 private:
  WheelEncoderDevice(FusionCore& core, const DeviceSlots& slots);

  const RuntimeConfig& cfg_;
  FusionCore& core_;
  DeviceSlots slots_;
  std::unique_ptr<drivers::CanopenEncoders> encoders_;
  std::unique_ptr<drivers::WheelOdometry> wheels_;
  drivers::WheelTwist last_twist_;
  bool have_twist_ = false;
  est::SensorSample sample_;
};

}  // namespace rtfuse
