#pragma once
// The bus primitives the drivers of one configuration run on, whatever
// provides them: the kernel (runtime/linux_hal), the simulated robot
// (sim/), or a recording (replay). One named slot per device thread, each
// with the clock that thread waits on; null where the configuration has no
// such device. Not owned.
#include "hal/can_bus.hpp"
#include "hal/clock.hpp"
#include "hal/gpio.hpp"
#include "hal/i2c_bus.hpp"
#include "hal/serial_port.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse {

// The IMU thread's: the chip's bus, its data-ready line (null: poll at
// mpu.poll_rate) and the clock for polling and reset delays.
struct ImuBuses {
  hal::I2cBus* i2c = nullptr;
  hal::GpioEdgeSource* data_ready = nullptr;
  hal::Clock* clock = nullptr;
};

// The camera thread's: the stereo camera's stream, and the clock it backs
// off on while the camera is unplugged.
struct CameraBuses {
  hal::VideoStream* video = nullptr;
  hal::Clock* clock = nullptr;
};

// The GNSS thread's: the receiver's serial port, and the clock it measures
// silence and reopen backoffs on.
struct GnssBuses {
  hal::SerialPort* serial = nullptr;
  hal::Clock* clock = nullptr;
};

struct HalBuses {
  hal::CanBus* can = nullptr;  // the wheel encoders' bus, polled by the loop thread
  ImuBuses imu;
  CameraBuses camera;
  GnssBuses gnss;
};

}  // namespace rtfuse
