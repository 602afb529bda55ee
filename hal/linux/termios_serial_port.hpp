#pragma once
// SerialPort over a Linux tty: a UART (/dev/ttyS*, /dev/ttyAMA*, /dev/ttyTHS*),
// a USB CDC-ACM receiver (/dev/ttyACM*) or a USB-serial bridge (/dev/ttyUSB*).
// Raw 8N1, no flow control: UBX is binary, and a 0x11/0x13 in it taken for
// XON/XOFF would both lose the byte and stall the line.
//
// open() and reopen() allocate and fail with a message naming the device,
// the errno text and the likely fix. After that read() and write() neither
// allocate nor lock; the descriptor is non-blocking and poll() is the only
// wait, bounded by the caller's timeout (read) or kWriteTimeoutNs (write).
//
// Stamps: a tty keeps no receive time, so bytes are stamped when poll()
// reports them. A caller already waiting in read() sees them within its
// wake-up latency of the driver pushing them; bytes that sat queued before
// the call are late by as long as they sat, and a USB-serial bridge adds its
// own batching (FTDI: latency_timer, 16 ms unless lowered in sysfs).
//
// The port is opened exclusive (TIOCEXCL), so gpsd or a forgotten terminal
// program cannot take half the bytes: their open() fails with EBUSY. The
// kernel does not apply this to a process with CAP_SYS_ADMIN (root): its
// second open succeeds, and the two then race for every byte.
//
// When the device goes away (a USB receiver unplugged; the master side of a
// pty closed) the kernel hangs the tty up: poll() reports POLLHUP|POLLERR,
// read() returns 0 and write() fails with EIO. The port then closes its
// descriptor at once, so a replugged receiver can get its old name back
// (while the old minor is held the kernel hands out the next, ttyACM1), and
// stays closed, every call answering kClosed, until reopen() succeeds.
#include <cstdint>
#include <memory>
#include <string>

#include "hal/serial_port.hpp"

namespace rtfuse::hal {

class TermiosSerialPort final : public SerialPort {
 public:
  // A configuration message is a few hundred bytes and the kernel's
  // transmit buffer some kilobytes: a write that waits this long for room is
  // facing a device that does not drain (hardware flow control asserted by
  // nothing, a stalled USB link), not a slow baud rate.
  static constexpr TimeNs kWriteTimeoutNs = 100'000'000;

  // Opens `path` (a /dev/serial/by-id link survives re-enumeration; the
  // ttyACMn name does not) at `baud`, one of supported_bauds(). For a USB
  // CDC-ACM receiver the rate is passed on and ignored: USB sets the pace.
  // On failure returns null and, when error is not null, sets *error.
  static std::unique_ptr<TermiosSerialPort> open(const std::string& path, int baud, std::string* error);

  // "4800, 9600, ..., 921600": the rates open() accepts.
  static std::string supported_bauds();
  static bool supports(int baud) noexcept;
  // The start-up message for `call` failing with `err` on `path`. Exposed so
  // tests can check the advice for errors a root test run cannot produce.
  static std::string describe_open_failure(const std::string& path, const char* call, int err);

  ~TermiosSerialPort() override;
  TermiosSerialPort(const TermiosSerialPort&) = delete;
  TermiosSerialPort& operator=(const TermiosSerialPort&) = delete;

  // See SerialPort::read. A hang-up met after some bytes were taken returns
  // those bytes; the next call answers kClosed.
  int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept override;
  // kTimeout when the device takes no more within kWriteTimeoutNs;
  // last_error() then says how many bytes did go out.
  HalStatus write(const std::uint8_t* data, int size) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }

  // Opens the same path with the same settings again (after kClosed, or to
  // reset a port something else reconfigured). Allocates: it runs after the
  // device went away, never on a healthy data path. False with last_error().
  bool reopen() noexcept override;

  bool closed() const noexcept { return fd_ < 0; }
  const std::string& path() const noexcept { return path_; }
  int baud() const noexcept { return baud_; }
  int fd() const noexcept { return fd_; }

 private:
  TermiosSerialPort(std::string path, int baud);

  // Opens and configures; false with *error set and nothing held.
  bool open_device(std::string* error);
  void close_device() noexcept;
  HalStatus hung_up(const char* what) noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  std::string path_;
  int baud_;
  int fd_ = -1;
  // Fixed storage: run-time failures are formatted without allocating.
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal
