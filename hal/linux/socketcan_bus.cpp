#include "hal/linux/socketcan_bus.hpp"
#include "hal/linux/errno_text.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <utility>
#include <vector>

namespace rtfuse::hal {

namespace {

// A flood of bad records must not turn one receive() into unbounded work for
// the real-time loop: past this many skips the call returns what it has.
constexpr int kMaxSkipsPerCall = 64;

// Error classes whose frames move state(); the kernel filters the others out
// so a bus-error storm (CAN_ERR_BUSERROR "may flood") cannot swamp the queue.
constexpr can_err_mask_t kHandledErrorClasses = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;

TimeNs clock_ns(clockid_t id) noexcept {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}

// The kernel stamps CAN frames (SO_TIMESTAMPNS / SO_TIMESTAMP) on
// CLOCK_REALTIME; false when the socket carries no stamp.
bool realtime_stamp(msghdr* msg, TimeNs* out) noexcept {
  for (cmsghdr* c = CMSG_FIRSTHDR(msg); c != nullptr; c = CMSG_NXTHDR(msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    const std::size_t len = c->cmsg_len - CMSG_LEN(0);
    if (c->cmsg_type == SCM_TIMESTAMPNS && len == sizeof(timespec)) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      *out = static_cast<TimeNs>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
      return true;
    }
    if (c->cmsg_type == SCM_TIMESTAMP && len == sizeof(timeval)) {
      timeval tv{};
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      *out = static_cast<TimeNs>(tv.tv_sec) * kNsPerSec + static_cast<TimeNs>(tv.tv_usec) * kNsPerUs;
      return true;
    }
  }
  return false;
}

// Converts a kernel CLOCK_REALTIME stamp to CLOCK_MONOTONIC by subtracting
// the realtime-monotonic offset sampled now. This assumes the offset did not
// change between reception and this read: NTP slewing in that interval (at
// most 500 ppm of a few ms, i.e. microseconds) shifts the stamp slightly; a
// wall-clock step in that interval shifts it by the step. The kernel offers no
// monotonic stamp for sockets, and a frame cannot arrive after it is read, so
// the result is clamped to the monotonic read time to keep a forward step
// from producing a stamp in the future.
TimeNs realtime_to_monotonic(TimeNs realtime_stamp_ns) noexcept {
  const TimeNs mono_before = clock_ns(CLOCK_MONOTONIC);
  const TimeNs real = clock_ns(CLOCK_REALTIME);
  const TimeNs stamp = realtime_stamp_ns - (real - mono_before);
  return stamp > mono_before ? mono_before : stamp;
}

HalStatus status_for_errno(int err) noexcept {
  switch (err) {
    case EAGAIN:
#if EWOULDBLOCK != EAGAIN
    case EWOULDBLOCK:
#endif
    case ENOBUFS:  // SocketCAN's answer when the interface TX queue is full
      return HalStatus::kWouldBlock;
    case ENETDOWN:
    case ENODEV:
    case ENXIO:
    case EPIPE:
    case ECONNRESET:
      return HalStatus::kClosed;
    default:
      return HalStatus::kIoError;
  }
}

const char* open_hint(const char* call, int err, const std::string& ifname, char* buf, std::size_t size) {
  const char* name = ifname.c_str();
  const bool is_bind = std::strncmp(call, "bind", 4) == 0;
  switch (err) {
    case EAFNOSUPPORT:
      return "the kernel has no CAN support: load the can and can_raw modules (modprobe can can_raw) "
             "or enable CONFIG_CAN/CONFIG_CAN_RAW";
    case EPROTONOSUPPORT:
      return "the kernel has CAN but no raw CAN protocol: load can_raw (modprobe can_raw) or enable "
             "CONFIG_CAN_RAW";
    case ENODEV:
      if (is_bind) {
        std::snprintf(buf, size,
                      "'%s' is not a CAN interface: list CAN interfaces with `ip -details link show type can`, "
                      "or use vcan for testing (modprobe vcan; ip link add dev vcan0 type vcan)",
                      name);
      } else {
        std::snprintf(buf, size,
                      "no interface '%s': check `ip link`, bring it up with `ip link set %s up type can bitrate "
                      "500000`, or use vcan for testing (modprobe vcan; ip link add dev vcan0 type vcan)",
                      name, name);
      }
      return buf;
    case ENETDOWN:
      std::snprintf(buf, size,
                    "interface '%s' is down: bring it up with `ip link set %s up type can bitrate 500000` "
                    "(vcan: `ip link set %s up`)",
                    name, name, name);
      return buf;
    case EMFILE:
    case ENFILE:
      return "the process or system is out of file descriptors: raise the limit (ulimit -n) or close leaked ones";
    case EPERM:
    case EACCES:
      return "permission denied: run with the needed capability or check security policies (seccomp, SELinux)";
    case EINVAL:
      return "the kernel rejected the arguments: check the filters (at most 512) and the interface name";
    default:
      std::snprintf(buf, size, "check the interface with `ip -details link show %s`", name);
      return buf;
  }
}

bool fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

}  // namespace

namespace socketcan_detail {

std::string open_error_message(const std::string& ifname, const char* call, int err) {
  char hint_buf[320];
  const ErrnoText text(err);
  const char* hint = open_hint(call, err, ifname, hint_buf, sizeof hint_buf);
  std::string msg = "CAN interface '" + ifname + "': " + call + " failed: " + text.text;
  msg += " - ";
  msg += hint;
  return msg;
}

}  // namespace socketcan_detail

SocketCanBus::SocketCanBus(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<SocketCanBus> SocketCanBus::adopt(int fd, std::string name) {
  if (fd < 0) return nullptr;
  return std::unique_ptr<SocketCanBus>(new SocketCanBus(fd, std::move(name)));
}

std::unique_ptr<SocketCanBus> SocketCanBus::open(const std::string& ifname, const CanIdFilter* filters,
                                                 int n_filters, std::string* error) {
  using socketcan_detail::open_error_message;
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) {
    fail(error, "CAN interface '" + ifname + "': the name must be 1.." + std::to_string(IFNAMSIZ - 1) +
                    " characters, as `ip link` shows it (e.g. can0)");
    return nullptr;
  }
  if (n_filters < 0 || n_filters > CAN_RAW_FILTER_MAX || (n_filters > 0 && filters == nullptr)) {
    fail(error, "CAN interface '" + ifname + "': " + std::to_string(n_filters) +
                    " ID filters given: the kernel takes 0 (receive all) to " + std::to_string(CAN_RAW_FILTER_MAX));
    return nullptr;
  }
  std::vector<can_filter> kfilters(static_cast<std::size_t>(n_filters));
  for (int i = 0; i < n_filters; ++i) {
    const CanIdFilter& f = filters[i];
    const std::uint32_t width_mask = f.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
    if ((f.id & ~width_mask) != 0) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "': filter %d: id 0x%X does not fit in %s bits%s", i, f.id,
                    f.extended ? "29" : "11", f.extended ? "" : " (set extended for 29-bit IDs)");
      fail(error, "CAN interface '" + ifname + buf);
      return nullptr;
    }
    // CAN_EFF_FLAG in the mask makes the frame format part of the match, so
    // an 11-bit filter never passes a 29-bit frame with the same low bits.
    kfilters[static_cast<std::size_t>(i)].can_id = f.extended ? (f.id | CAN_EFF_FLAG) : f.id;
    kfilters[static_cast<std::size_t>(i)].can_mask = (f.mask & width_mask) | CAN_EFF_FLAG;
  }

  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    fail(error, open_error_message(ifname, "socket(PF_CAN, SOCK_RAW, CAN_RAW)", errno));
    return nullptr;
  }
  // Owns fd from here so every early return closes it.
  std::unique_ptr<SocketCanBus> bus(new SocketCanBus(fd, ifname));
  auto failed = [&](const char* call) {
    fail(error, open_error_message(ifname, call, errno));
    return nullptr;
  };

  if (n_filters > 0 &&
      setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, kfilters.data(),
                 static_cast<socklen_t>(kfilters.size() * sizeof(can_filter))) != 0) {
    return failed("setsockopt(CAN_RAW_FILTER)");
  }
  const can_err_mask_t err_mask = kHandledErrorClasses;
  if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
    return failed("setsockopt(CAN_RAW_ERR_FILTER)");
  }
  const int on = 1;
  if (setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0) {
    return failed("setsockopt(SO_TIMESTAMPNS)");
  }

  ifreq ifr{};
  std::memcpy(ifr.ifr_name, ifname.c_str(), ifname.size() + 1);
  if (ioctl(fd, SIOCGIFINDEX, &ifr) != 0) return failed("ioctl(SIOCGIFINDEX)");
  const int ifindex = ifr.ifr_ifindex;

  // A down interface binds fine and only fails at the first send; saying so
  // at start-up points at the fix while someone is watching.
  if (ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) return failed("ioctl(SIOCGIFFLAGS)");
  if ((ifr.ifr_flags & IFF_UP) == 0) {
    errno = ENETDOWN;
    return failed("interface up check (SIOCGIFFLAGS)");
  }

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) return failed("bind");
  return bus;
}

void SocketCanBus::set_last_error(const char* what, int err) noexcept {
  const ErrnoText text(err);
  std::snprintf(last_error_, sizeof last_error_, "%s on %s: %s", what, name_.c_str(), text.text);
}

void SocketCanBus::apply_error_frame(std::uint32_t err_class, const std::uint8_t* data) noexcept {
  if ((err_class & CAN_ERR_CRTL) != 0) {
    const std::uint8_t ctrl = data[1];
    if ((ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) {
      state_ = CanBusState::kErrorPassive;
    } else if ((ctrl & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0) {
      state_ = CanBusState::kErrorWarning;
#ifdef CAN_ERR_CRTL_ACTIVE
    } else if ((ctrl & CAN_ERR_CRTL_ACTIVE) != 0) {
      state_ = CanBusState::kErrorActive;
#endif
    }
  }
  if ((err_class & CAN_ERR_RESTARTED) != 0) state_ = CanBusState::kErrorActive;
  // Checked last: a frame reporting bus-off together with anything else
  // leaves the controller off the bus.
  if ((err_class & CAN_ERR_BUSOFF) != 0) state_ = CanBusState::kBusOff;
}

HalStatus SocketCanBus::send(const CanFrame& frame) noexcept {
  if (fd_ < 0) return HalStatus::kClosed;
  const char* refused = nullptr;
  if (frame.error) {
    refused = "error frames come from the controller and cannot be sent";
  } else if (frame.dlc > CAN_MAX_DLEN) {
    refused = "dlc above 8 is not a classic CAN frame";
  } else if ((frame.id & ~(frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK)) != 0) {
    refused = frame.extended ? "id does not fit in 29 bits" : "id does not fit in 11 bits";
  }
  if (refused != nullptr) {
    std::snprintf(last_error_, sizeof last_error_, "send on %s refused: %s", name_.c_str(), refused);
    return HalStatus::kMalformed;
  }

  can_frame cf;
  std::memset(&cf, 0, sizeof cf);  // padding bytes go on the wire to the kernel: keep them zero
  cf.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0U) | (frame.rtr ? CAN_RTR_FLAG : 0U);
  cf.can_dlc = frame.dlc;  // can_dlc rather than len: older kernel headers (Jetson L4T) only have can_dlc
  if (!frame.rtr) std::memcpy(cf.data, frame.data, frame.dlc);

  ssize_t n;
  do {
    n = ::send(fd_, &cf, sizeof cf, MSG_DONTWAIT | MSG_NOSIGNAL);
  } while (n < 0 && errno == EINTR);
  if (n == static_cast<ssize_t>(sizeof cf)) return HalStatus::kOk;
  if (n >= 0) {
    std::snprintf(last_error_, sizeof last_error_, "send on %s: short write of %zd bytes", name_.c_str(), n);
    return HalStatus::kIoError;
  }
  const int err = errno;
  set_last_error("send", err);
  return status_for_errno(err);
}

int SocketCanBus::receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept {
  HalStatus ignored = HalStatus::kOk;
  if (status == nullptr) status = &ignored;
  if (pending_status_ != HalStatus::kOk) {
    *status = pending_status_;
    pending_status_ = HalStatus::kOk;
    return 0;
  }
  if (fd_ < 0) {
    *status = HalStatus::kClosed;
    return 0;
  }
  if (out == nullptr || max <= 0) {
    *status = HalStatus::kOk;
    return 0;
  }
  const TimeNs deadline = timeout_ns > 0 ? monotonic_now_ns() + timeout_ns : 0;

  int n = 0;
  int skipped = 0;
  while (n < max && skipped < kMaxSkipsPerCall) {
    // Large enough for a CAN FD record, so a bigger record reads as the wrong
    // size instead of passing as a truncated classic frame.
    alignas(can_frame) unsigned char record[sizeof(canfd_frame) + 1];
    alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(timeval)) + 64];
    iovec iov{record, sizeof record};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;

    const ssize_t got = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (got < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      if (err == EAGAIN || err == EWOULDBLOCK) {
        if (n > 0 || timeout_ns <= 0) break;
        const TimeNs remaining = deadline - monotonic_now_ns();
        if (remaining <= 0) break;
        pollfd pfd{fd_, POLLIN, 0};
        const timespec ts = ns_to_timespec(remaining);
        const int ready = ::ppoll(&pfd, 1, &ts, nullptr);
        if (ready == 0) break;
        if (ready < 0) {
          if (errno == EINTR) continue;
          set_last_error("ppoll", errno);
          *status = HalStatus::kIoError;
          return 0;
        }
        if ((pfd.revents & POLLNVAL) != 0) {
          set_last_error("ppoll", EBADF);
          *status = HalStatus::kClosed;
          return 0;
        }
        continue;  // readable, error or hang-up: the next recvmsg says which
      }
      set_last_error("recvmsg", err);
      const HalStatus s = status_for_errno(err);
      if (n > 0) {
        pending_status_ = s;
        break;
      }
      *status = s;
      return 0;
    }
    if (got == 0 && (msg.msg_flags & MSG_TRUNC) == 0) {
      // A raw CAN socket never yields an empty record; a socket pair does
      // when the peer closed.
      std::snprintf(last_error_, sizeof last_error_, "recvmsg on %s: end of stream (peer closed)", name_.c_str());
      if (n > 0) {
        pending_status_ = HalStatus::kClosed;
        break;
      }
      *status = HalStatus::kClosed;
      return 0;
    }

    can_frame cf;
    const bool right_size = got == static_cast<ssize_t>(sizeof cf) && (msg.msg_flags & MSG_TRUNC) == 0;
    if (right_size) std::memcpy(&cf, record, sizeof cf);
    if (!right_size || cf.can_dlc > CAN_MAX_DLEN) {
      ++malformed_;
      ++skipped;
      continue;
    }

    CanFrame& f = out[n];
    f = CanFrame{};
    f.dlc = cf.can_dlc;
    std::memcpy(f.data, cf.data, f.dlc);
    if ((cf.can_id & CAN_ERR_FLAG) != 0) {
      f.error = true;
      f.id = cf.can_id & CAN_ERR_MASK;
      apply_error_frame(f.id, cf.data);
    } else {
      f.extended = (cf.can_id & CAN_EFF_FLAG) != 0;
      f.rtr = (cf.can_id & CAN_RTR_FLAG) != 0;
      f.id = cf.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    }
    TimeNs real = 0;
    f.stamp = realtime_stamp(&msg, &real) ? realtime_to_monotonic(real) : monotonic_now_ns();
    ++n;
  }

  if (n > 0) {
    *status = HalStatus::kOk;
  } else if (skipped > 0) {
    *status = HalStatus::kMalformed;
  } else {
    *status = timeout_ns > 0 ? HalStatus::kTimeout : HalStatus::kWouldBlock;
  }
  return n;
}

}  // namespace rtfuse::hal
