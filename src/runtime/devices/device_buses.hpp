#pragma once
// The bus primitives one device's driver runs on, whatever provides them:
// the kernel (a device's Linux backend), the simulated robot, or a
// recording. A device uses the kinds it needs and leaves the rest null; the
// recording tap and the HAL replay handle each kind the same way for every
// device, so a new device on the existing kinds of bus adds nothing here.
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "hal/can_bus.hpp"
#include "hal/clock.hpp"
#include "hal/gpio.hpp"
#include "hal/i2c_bus.hpp"
#include "hal/serial_port.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse {

// In the order a recording lists one device's buses.
enum class BusKind : std::uint8_t { kCan, kI2c, kEdge, kVideo, kSerial, kClock };
constexpr int kBusKinds = 6;
constexpr std::uint32_t bus_bit(BusKind k) noexcept { return 1u << static_cast<unsigned>(k); }
const char* to_string(BusKind k) noexcept;

struct DeviceBuses {
  hal::CanBus* can = nullptr;
  hal::I2cBus* i2c = nullptr;
  hal::GpioEdgeSource* edge = nullptr;  // a data-ready line (null: poll)
  hal::VideoStream* video = nullptr;
  hal::SerialPort* serial = nullptr;
  hal::Clock* clock = nullptr;  // what the device's thread waits and backs off on

  // The kinds that are set, as bus_bit()s.
  std::uint32_t present() const noexcept {
    return (can ? bus_bit(BusKind::kCan) : 0u) | (i2c ? bus_bit(BusKind::kI2c) : 0u) |
           (edge ? bus_bit(BusKind::kEdge) : 0u) | (video ? bus_bit(BusKind::kVideo) : 0u) |
           (serial ? bus_bit(BusKind::kSerial) : 0u) | (clock ? bus_bit(BusKind::kClock) : 0u);
  }
  bool empty() const noexcept { return present() == 0; }
};

// Keeps alive the bus objects a backend made (a SocketCAN socket, a replay
// bus, a recording decorator), whatever their type. Start-up only.
class BusKeeper {
 public:
  template <class T>
  T* keep(std::unique_ptr<T> bus) {
    T* raw = bus.get();
    if (raw != nullptr) kept_.push_back(std::make_unique<Kept<T>>(std::move(bus)));
    return raw;
  }

 private:
  struct KeptBase {
    virtual ~KeptBase() = default;
  };
  template <class T>
  struct Kept final : KeptBase {
    explicit Kept(std::unique_ptr<T> p) : object(std::move(p)) {}
    std::unique_ptr<T> object;
  };
  std::vector<std::unique_ptr<KeptBase>> kept_;
};

}  // namespace rtfuse
