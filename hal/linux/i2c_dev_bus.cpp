#include "hal/linux/i2c_dev_bus.hpp"
#include "hal/linux/errno_text.hpp"

#include <fcntl.h>
#include <linux/i2c-dev.h>
#include <linux/i2c.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <utility>

namespace rtfuse::hal {
namespace {

bool all_digits(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

HalStatus map_errno(int err) noexcept {
  switch (err) {
    case ENXIO:
    case EREMOTEIO: return HalStatus::kNack;
    case ETIMEDOUT: return HalStatus::kTimeout;
    case EIO:
    case EAGAIN: return HalStatus::kBusError;  // EAGAIN from an adapter: arbitration lost
    case ENODEV: return HalStatus::kClosed;
    default: return HalStatus::kIoError;
  }
}

// A NACK can be a device busy with an internal write cycle, a bus error a
// glitch or a lost arbitration: both are worth another try. A timeout already
// cost the adapter's full timeout, and the rest will not get better.
bool retryable(HalStatus s) noexcept { return s == HalStatus::kNack || s == HalStatus::kBusError; }

}  // namespace

const char* to_string(I2cTransferMode mode) noexcept {
  return mode == I2cTransferMode::kI2c ? "I2C (combined I2C_RDWR transfers)" : "SMBus (I2C block reads, byte writes)";
}

int I2cDevBus::system_ioctl(int fd, unsigned long request, void* arg) noexcept { return ::ioctl(fd, request, arg); }

std::string I2cDevBus::device_path(const std::string& path_or_number) {
  if (all_digits(path_or_number)) return "/dev/i2c-" + path_or_number;
  if (path_or_number.rfind("i2c-", 0) == 0) return "/dev/" + path_or_number;
  return path_or_number;
}

std::string I2cDevBus::describe_open_failure(const std::string& path, int err) {
  std::string msg = "cannot open I2C bus " + path + ": " + ErrnoText(err).text;
  switch (err) {
    case ENOENT:
      msg += "; no " + path +
             ": load the i2c-dev module (modprobe i2c-dev) and check the bus number with i2cdetect -l";
      break;
    case EACCES:
    case EPERM:
      msg += "; add the user to group i2c (usermod -aG i2c $USER, then log in again) or add a udev rule "
             "giving that group access to " +
             path;
      break;
    default: break;
  }
  return msg;
}

bool I2cDevBus::check_adapter(int fd, const std::string& path, IoctlFn ioctl_fn, I2cTransferMode* mode,
                              std::string* error) {
  unsigned long funcs = 0;
  if (ioctl_fn(fd, I2C_FUNCS, &funcs) < 0) {
    const int err = errno;
    if (error) {
      *error = path + " is not an I2C adapter (I2C_FUNCS failed: " + ErrnoText(err).text +
               "); pass an i2c-dev node such as /dev/i2c-1 (list buses with i2cdetect -l)";
    }
    return false;
  }
  if ((funcs & I2C_FUNC_I2C) != 0) {
    if (mode) *mode = I2cTransferMode::kI2c;
    return true;
  }
  constexpr unsigned long kSmbusNeeds = I2C_FUNC_SMBUS_READ_I2C_BLOCK | I2C_FUNC_SMBUS_WRITE_BYTE_DATA;
  if ((funcs & kSmbusNeeds) == kSmbusNeeds) {
    if (mode) *mode = I2cTransferMode::kSmbus;
    return true;
  }
  if (error) {
    *error = path +
             " can do neither plain I2C transfers (I2C_RDWR) nor SMBus I2C-block reads with byte-data writes, which "
             "this backend needs to read register bursts; use another bus (i2cdetect -F shows what each adapter does)";
  }
  return false;
}

std::unique_ptr<I2cDevBus> I2cDevBus::open(const std::string& path_or_number, I2cRetryPolicy policy,
                                           std::string* error) {
  const std::string path = device_path(path_or_number);
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    if (error) *error = describe_open_failure(path, err);
    return nullptr;
  }
  I2cTransferMode mode = I2cTransferMode::kI2c;
  if (!check_adapter(fd, path, &system_ioctl, &mode, error)) {
    ::close(fd);
    return nullptr;
  }
  return adopt(fd, path, policy, &system_ioctl, mode);
}

std::unique_ptr<I2cDevBus> I2cDevBus::adopt(int fd, std::string name, I2cRetryPolicy policy, IoctlFn ioctl_fn,
                                            I2cTransferMode mode) {
  return std::unique_ptr<I2cDevBus>(
      new I2cDevBus(fd, std::move(name), policy, ioctl_fn ? ioctl_fn : &system_ioctl, mode));
}

I2cDevBus::I2cDevBus(int fd, std::string name, I2cRetryPolicy policy, IoctlFn ioctl_fn, I2cTransferMode mode)
    : fd_(fd), name_(std::move(name)), policy_(policy), ioctl_(ioctl_fn), mode_(mode) {
  if (policy_.attempts < 1) policy_.attempts = 1;
}

I2cDevBus::~I2cDevBus() {
  if (fd_ >= 0) ::close(fd_);
}

void I2cDevBus::set_error(const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(last_error_, sizeof last_error_, fmt, ap);
  va_end(ap);
}

HalStatus I2cDevBus::transfer(unsigned long request, void* arg, int ok_rc, std::uint8_t address, std::uint8_t reg,
                              const char* op) noexcept {
  int failures = 0;
  for (int attempt = 1; attempt <= policy_.attempts; ++attempt) {
    const int rc = ioctl_(fd_, request, arg);
    if (rc == ok_rc) {
      retries_ += failures;
      return HalStatus::kOk;
    }
    if (rc >= 0) {
      // The adapter stopped part-way without an errno; what the device saw
      // is unknown, so retrying a write could repeat a side effect.
      set_error("%s: %s addr 0x%02x reg 0x%02x: short transfer (%d of %d messages)", name_.c_str(), op, address,
                reg, rc, ok_rc);
      return HalStatus::kIoError;
    }
    const int err = errno;
    const HalStatus s = map_errno(err);
    set_error("%s: %s addr 0x%02x reg 0x%02x failed on attempt %d of %d: %s (%s)", name_.c_str(), op, address, reg,
              attempt, policy_.attempts, ErrnoText(err).text, to_string(s));
    if (!retryable(s)) return s;
    ++failures;
    if (attempt == policy_.attempts) return s;
  }
  return HalStatus::kIoError;  // unreachable: attempts >= 1
}

HalStatus I2cDevBus::read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept {
  if (address > 0x7f) {
    set_error("%s: read addr 0x%02x reg 0x%02x: not a 7-bit address", name_.c_str(), address, reg);
    return HalStatus::kIoError;
  }
  if (buf == nullptr || n < 1 || n > kMaxRead) {
    set_error("%s: read addr 0x%02x reg 0x%02x: length %d outside 1..%d", name_.c_str(), address, reg, n,
              kMaxRead);
    return HalStatus::kIoError;
  }
  if (mode_ == I2cTransferMode::kSmbus) {
    const HalStatus s = smbus_read(address, reg, n);
    if (s == HalStatus::kOk) std::memcpy(buf, rx_, static_cast<std::size_t>(n));
    return s;
  }
  std::uint8_t reg_byte = reg;
  i2c_msg msgs[2];
  msgs[0].addr = address;
  msgs[0].flags = 0;
  msgs[0].len = 1;
  msgs[0].buf = &reg_byte;
  msgs[1].addr = address;
  msgs[1].flags = I2C_M_RD;
  msgs[1].len = static_cast<__u16>(n);
  msgs[1].buf = rx_;
  i2c_rdwr_ioctl_data data{msgs, 2};
  const HalStatus s = transfer(I2C_RDWR, &data, 2, address, reg, "read");
  if (s == HalStatus::kOk) std::memcpy(buf, rx_, static_cast<std::size_t>(n));
  return s;
}

HalStatus I2cDevBus::write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept {
  if (address > 0x7f) {
    set_error("%s: write addr 0x%02x reg 0x%02x: not a 7-bit address", name_.c_str(), address, reg);
    return HalStatus::kIoError;
  }
  if (mode_ == I2cTransferMode::kSmbus) {
    const HalStatus s = select_address(address, reg, "write");
    if (s != HalStatus::kOk) return s;
    i2c_smbus_data data{};
    data.byte = value;
    i2c_smbus_ioctl_data args{I2C_SMBUS_WRITE, reg, I2C_SMBUS_BYTE_DATA, &data};
    return transfer(I2C_SMBUS, &args, 0, address, reg, "write");
  }
  std::uint8_t bytes[2] = {reg, value};
  i2c_msg msg;
  msg.addr = address;
  msg.flags = 0;
  msg.len = 2;
  msg.buf = bytes;
  i2c_rdwr_ioctl_data data{&msg, 1};
  return transfer(I2C_RDWR, &data, 1, address, reg, "write");
}

HalStatus I2cDevBus::select_address(std::uint8_t address, std::uint8_t reg, const char* op) noexcept {
  if (selected_address_ == address) return HalStatus::kOk;
  if (ioctl_(fd_, I2C_SLAVE, reinterpret_cast<void*>(static_cast<unsigned long>(address))) < 0) {
    const int err = errno;
    // EBUSY: a kernel driver owns the address (the IIO mpu6050 driver, say);
    // I2C_RDWR would not have noticed, SMBus transfers go through the client.
    set_error("%s: %s addr 0x%02x reg 0x%02x: selecting the address (I2C_SLAVE) failed: %s%s", name_.c_str(), op,
              address, reg, ErrnoText(err).text,
              err == EBUSY ? "; a kernel driver has claimed it: unbind that driver (see /sys/bus/i2c/devices)" : "");
    return map_errno(err);
  }
  selected_address_ = address;
  return HalStatus::kOk;
}

HalStatus I2cDevBus::smbus_read(std::uint8_t address, std::uint8_t reg, int n) noexcept {
  HalStatus s = select_address(address, reg, "read");
  for (int done = 0; s == HalStatus::kOk && done < n;) {
    const int chunk = n - done < kSmbusBlockMax ? n - done : kSmbusBlockMax;
    const auto chunk_reg = static_cast<std::uint8_t>(reg + done);
    i2c_smbus_data data{};
    data.block[0] = static_cast<__u8>(chunk);
    i2c_smbus_ioctl_data args{I2C_SMBUS_READ, chunk_reg, I2C_SMBUS_I2C_BLOCK_DATA, &data};
    s = transfer(I2C_SMBUS, &args, 0, address, chunk_reg, "read");
    if (s != HalStatus::kOk) break;
    if (data.block[0] != chunk) {
      set_error("%s: read addr 0x%02x reg 0x%02x: the adapter returned %d of %d bytes", name_.c_str(), address,
                chunk_reg, data.block[0], chunk);
      return HalStatus::kIoError;
    }
    std::memcpy(rx_ + done, &data.block[1], static_cast<std::size_t>(chunk));
    done += chunk;
  }
  return s;
}

}  // namespace rtfuse::hal
