#pragma once
// rtfused --record: the recorder plus the recording decorators around the
// configuration's buses. The drivers are given buses() instead of the real
// ones and never know they are recorded. Which device is on which thread is
// fixed here and read back by hal_replay.cpp:
//   stream "loop": the CAN bus (polled inside the tick);
//   stream "imu":  the I2C bus, the data-ready line, the IMU thread's clock;
//   stream "camera": the camera's video stream (frames in a ring of their
//   own; the camera thread's clock is not recorded: its driver reads it only
//   to back off while the camera is unplugged);
//   stream "gnss": the receiver's serial port and the GNSS thread's clock
//   (its silence and reopen backoff are decided on it).
#include <memory>
#include <string>

#include "hal/recording_can_bus.hpp"
#include "hal/recording_clock.hpp"
#include "hal/recording_gpio.hpp"
#include "hal/recording_i2c_bus.hpp"
#include "hal/recording_serial_port.hpp"
#include "hal/recording_video_stream.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/pipeline/recorder.hpp"

namespace rtfuse {

// Streams are named after their thread: the loop, and each thread device
// by its name() (the IMU's is "imu").
constexpr const char* kLoopStream = "loop";
constexpr const char* kImuStream = "imu";
constexpr const char* kCameraStream = "camera";
constexpr const char* kGnssStream = "gnss";

class RecordingTap {
 public:
  // config_text: the TOML the configuration came from, stored in the
  // recording so a replay needs nothing else. clock stamps the bus events.
  // start_ns: the time the devices are started with (Hardware::start), kept
  // in the recording so a replay starts them at the same time.
  static std::unique_ptr<RecordingTap> create(const std::string& path, const RuntimeConfig& cfg,
                                              const std::string& config_text, const HalBuses& inner,
                                              hal::Clock& clock, TimeNs start_ns, std::string* error);
  ~RecordingTap();
  HalBuses buses() const { return buses_; }
  runtime::Recorder& recorder() { return *recorder_; }
  const runtime::Recorder& recorder() const { return *recorder_; }
  // Events the decorators could not queue (ring full), all devices.
  std::int64_t overflows() const;

 private:
  RecordingTap() = default;
  std::unique_ptr<runtime::Recorder> recorder_;
  std::unique_ptr<hal::RecordingCanBus> can_;
  std::unique_ptr<hal::RecordingI2cBus> i2c_;
  std::unique_ptr<hal::RecordingEdgeSource> drdy_;
  std::unique_ptr<hal::RecordingClock> imu_clock_;
  std::unique_ptr<hal::RecordingVideoStream> camera_;
  std::unique_ptr<hal::RecordingSerialPort> gnss_;
  std::unique_ptr<hal::RecordingClock> gnss_clock_;
  HalBuses buses_;
};

// The device names a recording uses for a configuration's buses.
std::string can_device_name(const RuntimeConfig& cfg);
std::string i2c_device_name(const RuntimeConfig& cfg);
std::string video_device_name(const RuntimeConfig& cfg);
std::string gnss_device_name(const RuntimeConfig& cfg);

}  // namespace rtfuse
