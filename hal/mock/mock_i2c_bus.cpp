#include "hal/mock/mock_i2c_bus.hpp"

#include <algorithm>
#include <cstring>

namespace rtfuse::hal::mock {

namespace {
// Same split as the i2c-dev backend: a NACK or a glitch may pass on a second
// try, a timeout means the bus is stuck and retrying only adds latency.
bool retryable(HalStatus s) noexcept { return s == HalStatus::kNack || s == HalStatus::kBusError; }
}  // namespace

MockI2cBus::MockI2cBus(I2cRetryPolicy policy, int log_capacity)
    : policy_(policy),
      log_(new I2cTransferRecord[static_cast<std::size_t>(std::max(log_capacity, 1))]),
      log_capacity_(std::max(log_capacity, 1)) {
  if (policy_.attempts < 1) policy_.attempts = 1;
}

MockI2cBus::~MockI2cBus() = default;

bool MockI2cBus::attach(std::uint8_t address, I2cDevice& device) noexcept {
  if (address > 0x7f || find(address) != nullptr || device_count_ == kMaxDevices) return false;
  devices_[device_count_++] = Slot{address, &device};
  return true;
}

void MockI2cBus::detach(std::uint8_t address) noexcept {
  for (int i = 0; i < device_count_; ++i) {
    if (devices_[i].address == address) {
      devices_[i] = devices_[--device_count_];
      return;
    }
  }
}

I2cDevice* MockI2cBus::find(std::uint8_t address) const noexcept {
  for (int i = 0; i < device_count_; ++i) {
    if (devices_[i].address == address) return devices_[i].device;
  }
  return nullptr;
}

void MockI2cBus::fail_next(HalStatus status, int count) noexcept {
  fail_status_ = status;
  fail_count_ = status == HalStatus::kOk ? 0 : std::max(count, 0);
}

HalStatus MockI2cBus::wire_fault() noexcept {
  if (fail_count_ == 0) return HalStatus::kOk;
  --fail_count_;
  return fail_status_;
}

const I2cTransferRecord& MockI2cBus::transfer(int i) const noexcept {
  static const I2cTransferRecord kNone{};
  if (i < 0 || i >= log_count_) return kNone;
  return log_[(log_head_ + i) % log_capacity_];
}

void MockI2cBus::clear_log() noexcept {
  log_head_ = 0;
  log_count_ = 0;
}

void MockI2cBus::log(const I2cTransferRecord& r) noexcept {
  log_[(log_head_ + log_count_) % log_capacity_] = r;
  if (log_count_ < log_capacity_) {
    ++log_count_;
  } else {
    log_head_ = (log_head_ + 1) % log_capacity_;
  }
  ++total_transfers_;
}

void MockI2cBus::note_failure(HalStatus s) noexcept {
  switch (s) {
    case HalStatus::kNack: last_error_ = "mock i2c: no acknowledge from the device address"; break;
    case HalStatus::kTimeout: last_error_ = "mock i2c: transfer timed out"; break;
    case HalStatus::kBusError: last_error_ = "mock i2c: bus error"; break;
    default: last_error_ = "mock i2c: transfer failed"; break;
  }
}

template <class Transfer>
HalStatus MockI2cBus::with_retries(I2cTransferRecord& rec, I2cDevice* dev, Transfer&& transfer) noexcept {
  HalStatus s = HalStatus::kIoError;
  int failures = 0;
  for (int attempt = 1; attempt <= policy_.attempts; ++attempt) {
    rec.attempts = static_cast<std::uint8_t>(attempt);
    s = wire_fault();
    if (s == HalStatus::kOk) s = dev != nullptr ? transfer() : HalStatus::kNack;
    if (s == HalStatus::kOk) {
      retries_ += failures;
      break;
    }
    note_failure(s);
    if (!retryable(s)) break;
    ++failures;
  }
  rec.status = s;
  log(rec);
  return s;
}

HalStatus MockI2cBus::read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept {
  I2cTransferRecord rec;
  rec.address = address;
  rec.reg = reg;
  rec.length = static_cast<std::uint8_t>(std::clamp(n, 0, 255));
  if (address > 0x7f || buf == nullptr || n < 1 || n > kMaxRead) {
    last_error_ = "mock i2c: read with an invalid address or a length outside 1..64";
    rec.status = HalStatus::kIoError;
    log(rec);
    return rec.status;
  }
  // Reads land here first so a failed transfer never touches the caller's buffer.
  std::uint8_t rx[kMaxRead];
  I2cDevice* dev = find(address);
  const HalStatus s = with_retries(rec, dev, [&] { return dev->i2c_read(reg, rx, n); });
  if (s == HalStatus::kOk) std::memcpy(buf, rx, static_cast<std::size_t>(n));
  return s;
}

HalStatus MockI2cBus::write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept {
  I2cTransferRecord rec;
  rec.address = address;
  rec.reg = reg;
  rec.length = 1;
  rec.write = true;
  rec.value = value;
  if (address > 0x7f) {
    last_error_ = "mock i2c: write to an invalid address";
    rec.status = HalStatus::kIoError;
    log(rec);
    return rec.status;
  }
  I2cDevice* dev = find(address);
  return with_retries(rec, dev, [&] { return dev->i2c_write(reg, value); });
}

}  // namespace rtfuse::hal::mock
