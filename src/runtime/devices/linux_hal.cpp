#include "runtime/devices/linux_hal.hpp"

#include "drivers/camera/camera_modes.hpp"
#include "drivers/camera/zed_usb_hint.hpp"
#include "hal/linux/gpiod_line.hpp"
#include "hal/linux/i2c_dev_bus.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "hal/linux/termios_serial_port.hpp"
#include "hal/linux/v4l2_stream.hpp"

namespace rtfuse {

struct LinuxHal::Devices {
  std::unique_ptr<hal::SocketCanBus> can;
  std::unique_ptr<hal::I2cDevBus> i2c;
  std::unique_ptr<hal::GpiodEdgeSource> drdy;
  std::unique_ptr<hal::V4l2Stream> video;
  std::unique_ptr<hal::TermiosSerialPort> gnss;
  hal::MonotonicClock clock;
};

LinuxHal::LinuxHal() : devices_(std::make_unique<Devices>()) {}
LinuxHal::~LinuxHal() = default;

int encoder_can_ids(const CanSection& can, std::uint32_t* ids, int max) {
  int n = 0;
  for (int i = 0; i < can.num_nodes; ++i) {
    const CanNodeSection& node = can.nodes[static_cast<std::size_t>(i)];
    const std::uint32_t tpdo = node.tpdo_cob_id != 0 ? node.tpdo_cob_id : 0x180u + node.node_id;
    for (std::uint32_t id : {tpdo, 0x700u + node.node_id, 0x080u + node.node_id}) {
      if (n < max) ids[n++] = id;
    }
  }
  return n;
}

std::unique_ptr<LinuxHal> LinuxHal::open(const RuntimeConfig& cfg, std::string* error) {
  std::unique_ptr<LinuxHal> h(new LinuxHal());
  const HardwareConfig& hw = cfg.hardware;
  Devices& d = *h->devices_;
  if (hw.can.enabled) {
    std::uint32_t ids[3 * kMaxWheelNodes];
    const int n = encoder_can_ids(hw.can, ids, 3 * kMaxWheelNodes);
    hal::CanIdFilter filters[3 * kMaxWheelNodes];
    for (int i = 0; i < n; ++i) filters[i] = hal::CanIdFilter{ids[i], 0x7FF, false};
    d.can = hal::SocketCanBus::open(hw.can.interface.c_str(), filters, n, error);
    if (!d.can) return nullptr;
    h->buses_.can = d.can.get();
  }
  if (hw.mpu.enabled) {
    d.i2c = hal::I2cDevBus::open(hw.mpu.device.c_str(), hal::I2cRetryPolicy{}, error);
    if (!d.i2c) return nullptr;
    h->buses_.imu.i2c = d.i2c.get();
    if (!hw.mpu.data_ready_chip.empty()) {
      d.drdy = hal::GpiodEdgeSource::open(hw.mpu.data_ready_chip.c_str(),
                                          static_cast<unsigned>(hw.mpu.data_ready_line), hal::EdgeKind::kRising,
                                          error);
      if (!d.drdy) return nullptr;
      h->buses_.imu.data_ready = d.drdy.get();
    }
    h->buses_.imu.clock = &d.clock;
  }
  if (hw.camera.enabled) {
    const CameraSection& c = hw.camera;
    drivers::CameraMode mode;
    if (!drivers::find_camera_mode(c.resolution.view(), c.fps, &mode, error)) return nullptr;
    hal::VideoRequest req;
    req.pixel_format = hal::kFourccYuyv;
    req.width = drivers::side_by_side_width(mode);
    req.height = drivers::side_by_side_height(mode);
    req.fps = c.fps;
    req.buffers = c.buffers;
    hal::V4l2OpenFailure failure;
    d.video = hal::V4l2Stream::open(c.device.c_str(), req, error, &failure);
    if (!d.video) {
      // A ZED on USB 2 offers VGA only; the refusal alone does not say so.
      *error += drivers::zed_usb2_hint(mode, failure.given, failure.offered);
      return nullptr;
    }
    h->buses_.camera.video = d.video.get();
    h->buses_.camera.clock = &d.clock;
  }
  if (hw.gnss.enabled) {
    d.gnss = hal::TermiosSerialPort::open(hw.gnss.device.c_str(), hw.gnss.baud, error);
    if (!d.gnss) return nullptr;
    h->buses_.gnss.serial = d.gnss.get();
    h->buses_.gnss.clock = &d.clock;
  }
  return h;
}

std::string LinuxHal::describe() const {
  const Devices& d = *devices_;
  std::string out;
  if (d.can) out += "CAN bus " + d.can->name() + ": SocketCAN raw, kernel receive stamps\n";
  if (d.i2c) out += "IMU bus " + d.i2c->name() + ": " + hal::to_string(d.i2c->mode()) + "\n";
  if (d.drdy) out += "IMU data-ready: GPIO rising edges, kernel-stamped\n";
  if (d.i2c && !d.drdy) out += "IMU data-ready: none, polled at the sample rate\n";
  if (d.video) out += "camera: V4L2 mmap streaming\n";
  if (d.gnss) {
    out += "GNSS receiver " + d.gnss->path() + ": termios raw at " + std::to_string(d.gnss->baud()) +
           " baud, stamped at read\n";
  }
  return out;
}

}  // namespace rtfuse
