#pragma once
// The bus primitives the drivers of one configuration run on, whatever
// provides them: the kernel (runtime/linux_hal), the simulated robot
// (sim/), or a recording (replay). Null where the configuration has no such
// device. Not owned.
#include "hal/can_bus.hpp"
#include "hal/clock.hpp"
#include "hal/gpio.hpp"
#include "hal/i2c_bus.hpp"

namespace rtfuse {

struct HalBuses {
  hal::CanBus* can = nullptr;            // polled by the loop thread
  hal::I2cBus* i2c = nullptr;            // the IMU thread's
  hal::GpioEdgeSource* drdy = nullptr;   // IMU data-ready line; null: poll at mpu.poll_rate
  hal::Clock* imu_clock = nullptr;       // the IMU thread's clock (polling, reset delays)
};

}  // namespace rtfuse
