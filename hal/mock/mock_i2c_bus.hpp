#pragma once
// A virtual I2C bus hosting register-file device models at 7-bit addresses.
// It applies the same retry policy as the i2c-dev backend (NACK and bus
// errors retried up to policy.attempts, timeouts not), so a driver sees the
// same results on both, and it logs every transfer the driver asked for,
// which replay compares against a recording to report divergence.
//
// Allocation happens in the constructor only.
#include <cstdint>
#include <memory>

#include "hal/i2c_bus.hpp"

namespace rtfuse::hal::mock {

// A device model behind an address (see mpu_register_file.hpp). One call is
// one attempt on the wire: a NACK here is a NACK of that attempt.
class I2cDevice {
 public:
  virtual ~I2cDevice() = default;
  // Register pointer at `reg`, then n bytes with auto-increment. Writes buf
  // only on kOk.
  virtual HalStatus i2c_read(std::uint8_t reg, std::uint8_t* buf, int n) noexcept = 0;
  virtual HalStatus i2c_write(std::uint8_t reg, std::uint8_t value) noexcept = 0;
};

struct I2cTransferRecord {
  std::uint8_t address = 0;
  std::uint8_t reg = 0;
  std::uint8_t length = 0;  // bytes read; 1 for a register write
  bool write = false;
  std::uint8_t value = 0;   // the byte written (writes only)
  HalStatus status = HalStatus::kOk;  // after retries
  std::uint8_t attempts = 0;
};

class MockI2cBus final : public I2cBus {
 public:
  static constexpr int kMaxRead = 64;
  static constexpr int kMaxDevices = 8;

  explicit MockI2cBus(I2cRetryPolicy policy = {}, int log_capacity = 1024);
  ~MockI2cBus() override;
  MockI2cBus(const MockI2cBus&) = delete;
  MockI2cBus& operator=(const MockI2cBus&) = delete;

  // False when the address is taken, outside 0x08..0x77 or the table is full.
  bool attach(std::uint8_t address, I2cDevice& device) noexcept;
  void detach(std::uint8_t address) noexcept;

  // The next `count` attempts fail on the wire with `status` before reaching
  // any device (kBusError: a glitch, retried; kTimeout: a stuck bus, not
  // retried). Device-level NACKs are the device model's own fault injection.
  void fail_next(HalStatus status, int count = 1) noexcept;

  // Transfer log: transfer(0) is the oldest kept; the log keeps the most
  // recent log_capacity transfers.
  const I2cTransferRecord& transfer(int i) const noexcept;
  int transfer_count() const noexcept { return log_count_; }
  std::int64_t total_transfers() const noexcept { return total_transfers_; }
  void clear_log() noexcept;

  // --- hal::I2cBus --------------------------------------------------------
  HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }
  std::int64_t retries() const noexcept override { return retries_; }

 private:
  I2cDevice* find(std::uint8_t address) const noexcept;
  // One attempt's status from the injected bus faults, kOk if none pending.
  HalStatus wire_fault() noexcept;
  void log(const I2cTransferRecord& r) noexcept;
  void note_failure(HalStatus s) noexcept;
  // One transfer under the retry policy, recorded in rec: wire faults first,
  // then the device (NACK when absent); NACK and bus errors are retried.
  template <class Transfer>
  HalStatus with_retries(I2cTransferRecord& rec, I2cDevice* dev, Transfer&& transfer) noexcept;

  I2cRetryPolicy policy_;
  struct Slot {
    std::uint8_t address = 0;
    I2cDevice* device = nullptr;
  };
  Slot devices_[kMaxDevices];
  int device_count_ = 0;

  HalStatus fail_status_ = HalStatus::kOk;
  int fail_count_ = 0;

  std::unique_ptr<I2cTransferRecord[]> log_;
  int log_capacity_;
  int log_head_ = 0;
  int log_count_ = 0;
  std::int64_t total_transfers_ = 0;

  std::int64_t retries_ = 0;
  const char* last_error_ = "";
};

}  // namespace rtfuse::hal::mock
