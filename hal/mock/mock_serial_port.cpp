#include "hal/mock/mock_serial_port.hpp"

#include <algorithm>
#include <cstring>

namespace rtfuse::hal::mock {

namespace {
// A zero-capacity ring would need a special case on every path.
int at_least_one(int n) { return n < 1 ? 1 : n; }
}  // namespace

MockSerialPort::MockSerialPort(Clock& clock, MockSerialPortCapacity capacity)
    : clock_(clock),
      rx_bytes_(new std::uint8_t[static_cast<std::size_t>(at_least_one(capacity.rx_bytes))]()),
      rx_arrival_(new TimeNs[static_cast<std::size_t>(at_least_one(capacity.rx_bytes))]()),
      rx_capacity_(at_least_one(capacity.rx_bytes)),
      written_(new std::uint8_t[static_cast<std::size_t>(at_least_one(capacity.written_bytes))]()),
      written_capacity_(at_least_one(capacity.written_bytes)) {}

bool MockSerialPort::feed(const std::uint8_t* data, int size, TimeNs arrival) noexcept {
  if (data == nullptr || size <= 0) return true;
  if (unplugged_) return false;
  arrival = std::max(arrival, last_arrival_);
  last_arrival_ = arrival;
  const int fits = std::min(size, rx_capacity_ - rx_count_);
  for (int i = 0; i < fits; ++i) {
    const int slot = (rx_head_ + rx_count_) % rx_capacity_;
    rx_bytes_[slot] = data[i];
    rx_arrival_[slot] = arrival;
    ++rx_count_;
  }
  if (fits == size) return true;
  ++overruns_;
  dropped_bytes_ += size - fits;
  return false;
}

void MockSerialPort::unplug() noexcept {
  unplugged_ = true;
  rx_head_ = 0;
  rx_count_ = 0;
}

int MockSerialPort::take_due(std::uint8_t* out, int max, TimeNs now, TimeNs* stamp) noexcept {
  int n = 0;
  while (n < max && rx_count_ > 0 && rx_arrival_[rx_head_] <= now) {
    if (n == 0 && stamp != nullptr) *stamp = rx_arrival_[rx_head_];
    out[n++] = rx_bytes_[rx_head_];
    rx_head_ = (rx_head_ + 1) % rx_capacity_;
    --rx_count_;
  }
  return n;
}

int MockSerialPort::read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept {
  HalStatus ignored = HalStatus::kOk;
  HalStatus& st = status != nullptr ? *status : ignored;
  if (unplugged_) {
    last_error_ = "mock serial: the device is unplugged";
    st = HalStatus::kClosed;
    return 0;
  }
  if (out == nullptr || max <= 0) {
    st = HalStatus::kOk;
    return 0;
  }
  const TimeNs begin = clock_.now();
  const TimeNs wait = timeout_ns > 0 ? timeout_ns : 0;
  const TimeNs deadline = wait > INT64_MAX - begin ? INT64_MAX : begin + wait;
  for (;;) {
    const TimeNs now = clock_.now();
    const int n = take_due(out, max, now, stamp);
    if (n > 0) {
      st = HalStatus::kOk;
      return n;
    }
    if (now >= deadline) {
      st = wait > 0 ? HalStatus::kTimeout : HalStatus::kWouldBlock;
      return 0;
    }
    const TimeNs next = rx_count_ > 0 ? rx_arrival_[rx_head_] : deadline;
    clock_.sleep_until(std::min(next, deadline));
    if (clock_.now() <= now) {
      // A clock that does not move (a replay clock after a divergence)
      // would make this spin.
      st = HalStatus::kTimeout;
      return 0;
    }
  }
}

HalStatus MockSerialPort::write(const std::uint8_t* data, int size) noexcept {
  if (unplugged_) {
    last_error_ = "mock serial: the device is unplugged";
    return HalStatus::kClosed;
  }
  if (size <= 0) return HalStatus::kOk;
  if (data == nullptr) {
    last_error_ = "mock serial: write from a null pointer";
    return HalStatus::kIoError;
  }
  // All or nothing, as the interface promises; a full log stands for a
  // device that stopped draining.
  if (size > written_capacity_ - written_size_) {
    last_error_ = "mock serial: written() is full (clear_written() it)";
    return HalStatus::kTimeout;
  }
  std::memcpy(written_.get() + written_size_, data, static_cast<std::size_t>(size));
  written_size_ += size;
  return HalStatus::kOk;
}

}  // namespace rtfuse::hal::mock
