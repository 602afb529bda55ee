#include "hal/recording_i2c_bus.hpp"

#include <cstring>

namespace rtfuse::hal {

HalStatus RecordingI2cBus::read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf,
                                          int n) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kI2cRead;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.address = address;
  ev.reg = reg;
  ev.length = n;
  ev.status = inner_.read_registers(address, reg, buf, n);
  ev.retries = inner_.retries();
  // The contract writes buf only on kOk; anything else leaves data zero.
  if (ev.status == HalStatus::kOk && buf != nullptr && n > 0 && n <= kBusEventMaxBytes) {
    std::memcpy(ev.data, buf, static_cast<std::size_t>(n));
  }
  tap_.push(ev);
  return ev.status;
}

HalStatus RecordingI2cBus::write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kI2cWrite;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.address = address;
  ev.reg = reg;
  ev.length = 1;
  ev.value = value;
  ev.status = inner_.write_register(address, reg, value);
  ev.retries = inner_.retries();
  tap_.push(ev);
  return ev.status;
}

}  // namespace rtfuse::hal
