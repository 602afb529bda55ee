#pragma once
// I2cBus over Linux i2c-dev (/dev/i2c-N) using I2C_RDWR.
//
// A register read is ONE I2C_RDWR call carrying two messages (write the
// register address, then read n bytes): the adapter joins them with a
// repeated start, so no other master can slip a transfer in between and
// devices that reset their register pointer on STOP still answer. A plain
// write()+read() pair would put a STOP in the middle.
//
// The ioctl goes through a function pointer so tests can script errno
// sequences and look at the exact i2c_rdwr_ioctl_data the kernel would get.
#include <cstdint>
#include <memory>
#include <string>

#include "hal/i2c_bus.hpp"

namespace rtfuse::hal {

class I2cDevBus final : public I2cBus {
 public:
  using IoctlFn = int (*)(int fd, unsigned long request, void* arg);
  static constexpr int kMaxRead = 64;

  // ::ioctl is variadic, so its address does not convert to IoctlFn.
  static int system_ioctl(int fd, unsigned long request, void* arg) noexcept;

  // "/dev/i2c-1", "i2c-1" or "1". Checks that the adapter does plain I2C
  // (I2C_FUNC_I2C): an SMBus-only adapter cannot do the combined transfer.
  // On failure returns null and sets *error to a message naming the device,
  // the errno text and the likely fix.
  static std::unique_ptr<I2cDevBus> open(const std::string& path_or_number, I2cRetryPolicy policy,
                                         std::string* error);

  // Takes ownership of fd (closed in the destructor when >= 0).
  static std::unique_ptr<I2cDevBus> adopt(int fd, std::string name, I2cRetryPolicy policy,
                                          IoctlFn ioctl_fn = &system_ioctl);

  // "1" -> "/dev/i2c-1"; anything else is taken as given.
  static std::string device_path(const std::string& path_or_number);
  // The start-up message for an open() that failed with err.
  static std::string describe_open_failure(const std::string& path, int err);
  // Asks the adapter for I2C_FUNCS; false with *error set if it cannot do
  // I2C_RDWR transfers or is not an I2C adapter at all.
  static bool check_adapter(int fd, const std::string& path, IoctlFn ioctl_fn, std::string* error);

  ~I2cDevBus() override;
  I2cDevBus(const I2cDevBus&) = delete;
  I2cDevBus& operator=(const I2cDevBus&) = delete;

  HalStatus read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept override;
  HalStatus write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept override;
  // The most recent failed attempt, recovered or not (a retried NACK leaves
  // its text here for diagnostics even though the call returned kOk).
  const char* last_error() const noexcept override { return last_error_; }
  std::int64_t retries() const noexcept override { return retries_; }

  const std::string& name() const noexcept { return name_; }

 private:
  I2cDevBus(int fd, std::string name, I2cRetryPolicy policy, IoctlFn ioctl_fn);

  // Runs the prepared transfer with the retry policy; op is "read"/"write"
  // for the error text.
  HalStatus transfer(void* rdwr, unsigned nmsgs, std::uint8_t address, std::uint8_t reg, const char* op) noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  int fd_;
  std::string name_;
  I2cRetryPolicy policy_;
  IoctlFn ioctl_;
  std::int64_t retries_ = 0;
  // Reads land here first so a failed or partial transfer never touches the
  // caller's buffer (the I2cBus contract).
  std::uint8_t rx_[kMaxRead] = {};
  // Fixed storage: failures are formatted without allocating in the RT path.
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal
