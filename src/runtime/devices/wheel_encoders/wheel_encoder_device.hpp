#pragma once
// The CANopen wheel encoders and the wheel odometry they feed, polled by the
// loop inside its tick: SYNC out, TPDOs in, one twist per complete set of
// positions into the wheel sensor's ring before the drain.
#include <memory>
#include <string>

#include "drivers/canopen/canopen_encoders.hpp"
#include "drivers/wheel/wheel_odometry.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

// Driver configs from the TOML's plain values (also used by tools that
// build the drivers themselves).
drivers::CanopenEncodersConfig encoder_driver_config(const RuntimeConfig& cfg);
drivers::WheelOdometryConfig wheel_driver_config(const RuntimeConfig& cfg);

// Counter keys of the CAN bus's, each node's and the odometry's slot.
extern const char* const kCanBusKeys[7];
extern const char* const kEncoderNodeKeys[10];
extern const char* const kWheelOdometryKeys[3];

class WheelEncoderDevice final : public Device {
 public:
  // The configuration is the core's. Slots from first_slot: the bus, one per
  // node, then the wheel odometry when a sensor fuses it.
  static std::unique_ptr<WheelEncoderDevice> create(hal::CanBus& bus, FusionCore& core, int first_slot,
                                                    std::string* error);
  // NMT start to the encoder nodes.
  bool start(TimeNs now, std::string* error) override;
  void poll(TimeNs now) noexcept override;
  void fill_snapshot(Snapshot& s) noexcept override;

  const drivers::CanopenEncoders& encoders() const { return *encoders_; }
  const drivers::WheelOdometry* wheel_odometry() const { return wheels_.get(); }

 private:
  WheelEncoderDevice(FusionCore& core, int first_slot);

  const RuntimeConfig& cfg_;
  FusionCore& core_;
  int first_slot_ = 0;
  int sensor_ = -1;
  std::unique_ptr<drivers::CanopenEncoders> encoders_;
  std::unique_ptr<drivers::WheelOdometry> wheels_;
  drivers::WheelTwist last_twist_;
  bool have_twist_ = false;
  est::SensorSample sample_;
};

}  // namespace rtfuse
