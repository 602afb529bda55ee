#pragma once
// rtfused --record: the recorder plus the recording decorators around the
// configuration's buses. The drivers are given buses() instead of the real
// ones and never know they are recorded. Every registered device's buses
// are recorded the same way, on the stream of the thread that calls them:
//   stream "loop": the buses of the polled devices (the CAN encoders);
//   stream "<device>": a thread device's buses (the IMU's I2C bus, data-ready
//   line and clock; the GNSS receiver's serial port and clock), a camera's
//   video stream with its frames in a ring of its own. A clock is recorded
//   unless the descriptor says its reads decide nothing (the camera's, read
//   only to back off while it is unplugged).
// The replay (replay/) reads the same layout back from the device table.
#include <memory>
#include <string>
#include <vector>

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

// The polled devices' stream; a thread device's is named after it.
constexpr const char* kLoopStream = "loop";

// The recording stream of a registered device.
const char* recording_stream(const DeviceDescriptor& d) noexcept;
// The name a recording's device table gives bus `kind` of a device: its
// device path's last part for its main bus ("can0", "i2c-1", "video0",
// "ttyACM0"), "<device>-drdy" and "<device>-clock" for a data-ready line
// and a clock.
std::string recorded_bus_name(const DeviceDescriptor& d, const RuntimeConfig& cfg, BusKind kind);

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
  std::vector<std::unique_ptr<hal::RecordingCanBus>> cans_;
  std::vector<std::unique_ptr<hal::RecordingI2cBus>> i2cs_;
  std::vector<std::unique_ptr<hal::RecordingEdgeSource>> edges_;
  std::vector<std::unique_ptr<hal::RecordingVideoStream>> videos_;
  std::vector<std::unique_ptr<hal::RecordingSerialPort>> serials_;
  std::vector<std::unique_ptr<hal::RecordingClock>> clocks_;
  HalBuses buses_;
};

}  // namespace rtfuse
