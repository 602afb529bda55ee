#include "hal/linux/termios_serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdarg>
#include <cstdio>
#include <utility>

#include "hal/linux/errno_text.hpp"

namespace rtfuse::hal {
namespace {

struct Rate {
  int baud;
  speed_t speed;
};

// What GNSS receivers use (u-blox UARTs start at 9600 or 38400 and go to
// 921600). The kernel has other rates (B1000000, any through termios2), but
// no receiver speaks them: refusing them turns a typo into a start-up error
// instead of garbage bytes at the wrong rate.
constexpr Rate kRates[] = {{4800, B4800},     {9600, B9600},     {19200, B19200},   {38400, B38400},  {57600, B57600},
                           {115200, B115200}, {230400, B230400}, {460800, B460800}, {921600, B921600}};

bool speed_for(int baud, speed_t* speed) noexcept {
  for (const Rate& r : kRates) {
    if (r.baud == baud) {
      *speed = r.speed;
      return true;
    }
  }
  return false;
}

int baud_for(speed_t speed) noexcept {
  for (const Rate& r : kRates) {
    if (r.speed == speed) return r.baud;
  }
  return -1;
}

// A poll() timeout in ms for ns left, rounded up: a byte due in 0.4 ms must
// not be given up on at once.
int poll_ms(TimeNs left) noexcept {
  if (left <= 0) return 0;
  const TimeNs ms = (left + 999'999) / 1'000'000;
  return ms > INT_MAX ? INT_MAX : static_cast<int>(ms);
}

TimeNs deadline_after(TimeNs begin, TimeNs wait) noexcept {
  return wait > INT64_MAX - begin ? INT64_MAX : begin + wait;
}

// A hung-up tty, or one whose hardware went away underneath it.
bool gone(int err) noexcept { return err == EIO || err == ENXIO || err == ENODEV; }

}  // namespace

bool TermiosSerialPort::supports(int baud) noexcept {
  speed_t unused;
  return speed_for(baud, &unused);
}

std::string TermiosSerialPort::supported_bauds() {
  std::string s;
  for (const Rate& r : kRates) {
    if (!s.empty()) s += ", ";
    s += std::to_string(r.baud);
  }
  return s;
}

std::string TermiosSerialPort::describe_open_failure(const std::string& path, const char* call, int err) {
  std::string msg = "serial port " + path + ": " + call + " failed: " + ErrnoText(err).text;
  switch (err) {
    case ENOENT: msg += "; is the receiver plugged in? see ls -l /dev/serial/by-id"; break;
    case EACCES:
    case EPERM: msg += "; add the user to the dialout group (usermod -aG dialout $USER, then log in again)"; break;
    case EBUSY: msg += "; another process holds it (gpsd? find it with fuser -v " + path + ")"; break;
    case ENODEV:
    case ENXIO: msg += "; the device went away (unplugged?); see ls -l /dev/serial/by-id"; break;
    case EIO: msg += "; no hardware answers behind this node (a ttyS port without a UART?) or the device failed"; break;
    default: break;
  }
  return msg;
}

std::unique_ptr<TermiosSerialPort> TermiosSerialPort::open(const std::string& path, int baud, std::string* error) {
  std::unique_ptr<TermiosSerialPort> port(new TermiosSerialPort(path, baud));
  std::string msg;
  if (!port->open_device(&msg)) {
    if (error != nullptr) *error = std::move(msg);
    return nullptr;
  }
  return port;
}

TermiosSerialPort::TermiosSerialPort(std::string path, int baud) : path_(std::move(path)), baud_(baud) {}

TermiosSerialPort::~TermiosSerialPort() { close_device(); }

bool TermiosSerialPort::open_device(std::string* error) {
  speed_t speed = B0;
  if (!speed_for(baud_, &speed)) {
    *error = "serial port " + path_ + ": " + std::to_string(baud_) + " baud is not supported; use one of " +
             supported_bauds();
    return false;
  }
  const auto fail = [&](const char* call, int err) {
    *error = describe_open_failure(path_, call, err);
    close_device();
    return false;
  };

  // O_NOCTTY: a receiver must never become the controlling terminal, or its
  // hang-up would SIGHUP the process. O_NONBLOCK: the open does not wait for
  // carrier (DCD) before CLOCAL is set, and reads and writes never sleep in
  // the kernel.
  const int fd = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return fail("open", errno);
  fd_ = fd;
  if (::isatty(fd) == 0) {
    const int err = errno;
    *error = "serial port " + path_ + ": not a serial port (isatty: " + ErrnoText(err).text +
             "); give the receiver's tty, e.g. /dev/ttyACM0 or its link in /dev/serial/by-id";
    close_device();
    return false;
  }
  if (::ioctl(fd, TIOCEXCL) != 0) return fail("ioctl(TIOCEXCL)", errno);

  termios t{};
  if (::tcgetattr(fd, &t) != 0) return fail("tcgetattr", errno);
  ::cfmakeraw(&t);
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS);
  t.c_cflag |= CS8 | CLOCAL | CREAD;
  // An empty read() returns 0 at once (not even EAGAIN): poll() does all the
  // waiting, to the deadline the caller gives each read().
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (::cfsetispeed(&t, speed) != 0 || ::cfsetospeed(&t, speed) != 0) return fail("cfsetspeed", errno);
  if (::tcsetattr(fd, TCSANOW, &t) != 0) return fail("tcsetattr", errno);

  // tcsetattr() succeeds when any one of the changes took; a driver may
  // have refused the rate or the frame format.
  termios got{};
  if (::tcgetattr(fd, &got) != 0) return fail("tcgetattr", errno);
  const tcflag_t frame_bits = CSIZE | PARENB | CSTOPB | CRTSCTS;
  if (::cfgetospeed(&got) != speed || ::cfgetispeed(&got) != speed || (got.c_cflag & frame_bits) != CS8) {
    const int given = baud_for(::cfgetospeed(&got));
    *error = "serial port " + path_ + ": the driver did not take " + std::to_string(baud_) + " baud 8N1 (it set " +
             (given > 0 ? std::to_string(given) + " baud" : std::string("a non-standard rate")) +
             ((got.c_cflag & frame_bits) != CS8 ? ", another frame format" : "") +
             "); use a rate the adapter supports: " + supported_bauds();
    close_device();
    return false;
  }
  // Bytes queued before now came at whatever rate the port had: garbage.
  if (::tcflush(fd, TCIOFLUSH) != 0) return fail("tcflush", errno);
  return true;
}

void TermiosSerialPort::close_device() noexcept {
  if (fd_ < 0) return;
  // A pty's tty outlives its last slave close while the master is open, and
  // keeps the exclusive flag: without this the next open, our own reopen()
  // included, would fail with EBUSY. (Fails harmlessly on a hung-up tty.)
  ::ioctl(fd_, TIOCNXCL);
  ::close(fd_);
  fd_ = -1;
}

void TermiosSerialPort::set_error(const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(last_error_, sizeof last_error_, fmt, ap);
  va_end(ap);
}

HalStatus TermiosSerialPort::hung_up(const char* what) noexcept {
  close_device();
  set_error("%s: %s: the device went away (unplugged, or the pty master closed); reopen() when it is back",
            path_.c_str(), what);
  return HalStatus::kClosed;
}

bool TermiosSerialPort::reopen() noexcept {
  close_device();
  std::string msg;
  if (!open_device(&msg)) {
    set_error("%s", msg.c_str());
    return false;
  }
  last_error_[0] = '\0';
  return true;
}

int TermiosSerialPort::read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept {
  HalStatus ignored = HalStatus::kOk;
  HalStatus& st = status != nullptr ? *status : ignored;
  if (fd_ < 0) {
    st = HalStatus::kClosed;  // last_error() still says why
    return 0;
  }
  if (out == nullptr || max <= 0) {
    st = HalStatus::kOk;
    return 0;
  }
  const TimeNs wait = timeout_ns > 0 ? timeout_ns : 0;
  const HalStatus nothing = wait > 0 ? HalStatus::kTimeout : HalStatus::kWouldBlock;
  const TimeNs deadline = deadline_after(monotonic_now_ns(), wait);
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    const int rc = ::poll(&p, 1, poll_ms(deadline - monotonic_now_ns()));
    if (rc == 0) {
      st = nothing;
      return 0;
    }
    if (rc < 0) {
      const int err = errno;
      if (err == EINTR) continue;  // a signal: wait out the rest
      set_error("%s: poll failed: %s", path_.c_str(), ErrnoText(err).text);
      st = HalStatus::kIoError;
      return 0;
    }
    if ((p.revents & POLLNVAL) != 0) {
      set_error("%s: poll: the file descriptor is not open (POLLNVAL)", path_.c_str());
      st = HalStatus::kIoError;
      return 0;
    }
    // A hung-up tty has dropped its queued bytes (read() returns 0 from now
    // on), so there is nothing to take first.
    if ((p.revents & (POLLHUP | POLLERR)) != 0) {
      st = hung_up("poll reported a hang-up");
      return 0;
    }
    const TimeNs seen = monotonic_now_ns();

    int n = 0;
    int err = 0;
    while (n < max) {
      const ssize_t got = ::read(fd_, out + n, static_cast<std::size_t>(max - n));
      if (got > 0) {
        n += static_cast<int>(got);
        continue;
      }
      if (got == 0) break;  // VMIN 0: nothing more queued (EOF looks the same; the next poll tells)
      if (errno == EINTR) continue;
      if (errno != EAGAIN) err = errno;
      break;
    }
    if (err != 0) {
      if (gone(err)) {
        const ErrnoText text(err);
        hung_up(text.text);
        if (n == 0) {
          st = HalStatus::kClosed;
          return 0;
        }
      } else if (n == 0) {
        set_error("%s: read failed: %s", path_.c_str(), ErrnoText(err).text);
        st = HalStatus::kIoError;
        return 0;
      }
    }
    if (n > 0) {
      if (stamp != nullptr) *stamp = seen;
      st = HalStatus::kOk;
      return n;
    }
    // Readable but empty: another opener (root ignores TIOCEXCL) or a flush
    // took the bytes. Wait out the rest of the timeout.
    if (monotonic_now_ns() >= deadline) {
      st = nothing;
      return 0;
    }
  }
}

HalStatus TermiosSerialPort::write(const std::uint8_t* data, int size) noexcept {
  if (fd_ < 0) return HalStatus::kClosed;
  if (size <= 0) return HalStatus::kOk;
  if (data == nullptr) {
    set_error("%s: write of %d bytes from a null pointer", path_.c_str(), size);
    return HalStatus::kIoError;
  }
  const TimeNs deadline = deadline_after(monotonic_now_ns(), kWriteTimeoutNs);
  int done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, data + done, static_cast<std::size_t>(size - done));
    if (n > 0) {
      done += static_cast<int>(n);
      continue;
    }
    if (n < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      if (gone(err)) return hung_up(ErrnoText(err).text);
      if (err != EAGAIN) {
        set_error("%s: write failed after %d of %d bytes: %s", path_.c_str(), done, size, ErrnoText(err).text);
        return HalStatus::kIoError;
      }
    }
    // The transmit buffer is full: wait for room.
    const TimeNs left = deadline - monotonic_now_ns();
    if (left <= 0) {
      set_error("%s: write timed out after %lld ms with %d of %d bytes sent (the device does not drain)", path_.c_str(),
                static_cast<long long>(kWriteTimeoutNs / 1'000'000), done, size);
      return HalStatus::kTimeout;
    }
    pollfd p{fd_, POLLOUT, 0};
    const int rc = ::poll(&p, 1, poll_ms(left));
    if (rc < 0 && errno != EINTR) {
      set_error("%s: poll failed: %s", path_.c_str(), ErrnoText(errno).text);
      return HalStatus::kIoError;
    }
    if (rc > 0 && (p.revents & POLLNVAL) != 0) {
      set_error("%s: poll: the file descriptor is not open (POLLNVAL)", path_.c_str());
      return HalStatus::kIoError;
    }
    if (rc > 0 && (p.revents & (POLLHUP | POLLERR)) != 0) return hung_up("poll reported a hang-up");
  }
  return HalStatus::kOk;
}

}  // namespace rtfuse::hal
