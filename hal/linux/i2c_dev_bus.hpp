#pragma once
// I2cBus over Linux i2c-dev (/dev/i2c-N), in one of two modes chosen at open
// from what the adapter reports (I2C_FUNCS):
//
// kI2c (I2C_FUNC_I2C): a register read is ONE I2C_RDWR call carrying two
// messages (write the register address, then read n bytes): the adapter
// joins them with a repeated start, so no other master can slip a transfer
// in between and devices that reset their register pointer on STOP still
// answer. A plain write()+read() pair would put a STOP in the middle.
//
// kSmbus: SMBus-only adapters (some SoC controllers, PC SMBus hosts, the
// kernel's i2c-stub) cannot do I2C_RDWR. A register read is then an SMBus
// "I2C block read" (I2C_SMBUS_I2C_BLOCK_DATA: the same write-register,
// repeated start, read-n on the wire), at most 32 bytes per transaction, and
// a write is an SMBus "write byte data". A read longer than 32 bytes becomes
// several transactions at successive register addresses, which is right for
// devices whose register pointer auto-increments (the MPU's 14-byte sample
// fits one) but is no longer one atomic snapshot.
//
// The ioctl goes through a function pointer so tests can script errno
// sequences and look at the exact i2c_rdwr_ioctl_data the kernel would get.
#include <cstdint>
#include <memory>
#include <string>

#include "hal/i2c_bus.hpp"

namespace rtfuse::hal {

enum class I2cTransferMode : std::uint8_t { kI2c, kSmbus };
// "I2C (combined I2C_RDWR transfers)" / "SMBus (I2C block reads, byte writes)".
const char* to_string(I2cTransferMode mode) noexcept;

class I2cDevBus final : public I2cBus {
 public:
  using IoctlFn = int (*)(int fd, unsigned long request, void* arg);
  static constexpr int kMaxRead = 64;
  static constexpr int kSmbusBlockMax = 32;  // I2C_SMBUS_BLOCK_MAX

  // ::ioctl is variadic, so its address does not convert to IoctlFn.
  static int system_ioctl(int fd, unsigned long request, void* arg) noexcept;

  // "/dev/i2c-1", "i2c-1" or "1". Picks the transfer mode from the adapter's
  // functionality (see the file comment; mode() says which).
  // On failure returns null and sets *error to a message naming the device,
  // the errno text and the likely fix.
  static std::unique_ptr<I2cDevBus> open(const std::string& path_or_number, I2cRetryPolicy policy,
                                         std::string* error);

  // Takes ownership of fd (closed in the destructor when >= 0).
  static std::unique_ptr<I2cDevBus> adopt(int fd, std::string name, I2cRetryPolicy policy,
                                          IoctlFn ioctl_fn = &system_ioctl,
                                          I2cTransferMode mode = I2cTransferMode::kI2c);

  // "1" -> "/dev/i2c-1"; anything else is taken as given.
  static std::string device_path(const std::string& path_or_number);
  // The start-up message for an open() that failed with err.
  static std::string describe_open_failure(const std::string& path, int err);
  // Asks the adapter for I2C_FUNCS and sets *mode: kI2c when it does plain
  // I2C, else kSmbus when it does SMBus I2C-block reads and byte-data writes.
  // False with *error set when it can do neither or is not an I2C adapter.
  static bool check_adapter(int fd, const std::string& path, IoctlFn ioctl_fn, I2cTransferMode* mode,
                            std::string* error);

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
  I2cTransferMode mode() const noexcept { return mode_; }

 private:
  I2cDevBus(int fd, std::string name, I2cRetryPolicy policy, IoctlFn ioctl_fn, I2cTransferMode mode);

  // Runs one prepared ioctl with the retry policy: success is a return of
  // `ok_rc` (the message count for I2C_RDWR, 0 for I2C_SMBUS). op is
  // "read"/"write" for the error text.
  HalStatus transfer(unsigned long request, void* arg, int ok_rc, std::uint8_t address, std::uint8_t reg,
                     const char* op) noexcept;
  HalStatus smbus_read(std::uint8_t address, std::uint8_t reg, int n) noexcept;
  // SMBus needs the target address set on the descriptor (I2C_SLAVE) rather
  // than in each message; done only when it changes.
  HalStatus select_address(std::uint8_t address, std::uint8_t reg, const char* op) noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  int fd_;
  std::string name_;
  I2cRetryPolicy policy_;
  IoctlFn ioctl_;
  I2cTransferMode mode_;
  int selected_address_ = -1;
  std::int64_t retries_ = 0;
  // Reads land here first so a failed or partial transfer never touches the
  // caller's buffer (the I2cBus contract).
  std::uint8_t rx_[kMaxRead] = {};
  // Fixed storage: failures are formatted without allocating in the RT path.
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal
