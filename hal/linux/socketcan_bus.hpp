#pragma once
// CanBus over a Linux SocketCAN raw socket (classic CAN, 8-byte frames).
//
// Start-up (open) may allocate and fails with a message that names the
// interface, the failing call, the errno text and the likely fix. After that,
// send() and receive() neither allocate nor block beyond the receive timeout,
// so the real-time loop can poll the bus every tick.
#include <cstdint>
#include <memory>
#include <string>

#include "hal/can_bus.hpp"

namespace rtfuse::hal {

// One CAN_RAW_FILTER entry: a received frame passes when
// (frame_id & mask) == (id & mask) and its frame format (11/29-bit) matches
// `extended`. RTR frames pass like data frames.
struct CanIdFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  bool extended = false;
};

class SocketCanBus final : public CanBus {
 public:
  // Opens a raw CAN socket bound to `ifname`, non-blocking, with kernel
  // receive timestamps. n_filters == 0 receives every frame; otherwise only
  // frames matching at least one filter (at most 512, the kernel's
  // CAN_RAW_FILTER_MAX). Error frames for bus-off, controller state changes
  // and restarts are always delivered. On failure returns nullptr and, when
  // error is not null, sets *error to the full explanation.
  static std::unique_ptr<SocketCanBus> open(const std::string& ifname, const CanIdFilter* filters,
                                            int n_filters, std::string* error);

  // Takes ownership of an already-open socket whose reads deliver one
  // `struct can_frame` per record, as a CAN_RAW socket does (tests use an
  // AF_UNIX SOCK_SEQPACKET pair; tools use sockets they set up themselves).
  // The socket's options are left as they are: kernel timestamps are used
  // when the caller enabled SO_TIMESTAMPNS or SO_TIMESTAMP. Returns nullptr
  // for a negative fd.
  static std::unique_ptr<SocketCanBus> adopt(int fd, std::string name);

  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  // EAGAIN/ENOBUFS (TX queue full) -> kWouldBlock; ENETDOWN/ENODEV/EPIPE ->
  // kClosed; a frame that cannot be put on the wire (dlc > 8, id wider than
  // its format, error flag) -> kMalformed without a system call.
  HalStatus send(const CanFrame& frame) noexcept override;

  // See CanBus::receive. Records of the wrong size or with dlc > 8 are
  // skipped and counted in malformed(); when nothing valid arrived but such
  // records did, *status is kMalformed. A socket error met after some frames
  // were read is held back and reported by the next call, so frames already
  // taken are never dropped behind an error status.
  int receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept override;

  // kUnknown until the first bus-state error frame: a freshly bound socket
  // cannot tell whether the controller is already error-passive or bus-off.
  CanBusState state() const noexcept override { return state_; }
  const char* last_error() const noexcept override { return last_error_; }

  // Records skipped since construction (wrong size or dlc > 8).
  std::int64_t malformed() const noexcept { return malformed_; }
  const std::string& name() const noexcept { return name_; }
  int fd() const noexcept { return fd_; }

 private:
  SocketCanBus(int fd, std::string name);

  void set_last_error(const char* what, int err) noexcept;
  void apply_error_frame(std::uint32_t err_class, const std::uint8_t* data) noexcept;

  int fd_ = -1;
  std::string name_;
  CanBusState state_ = CanBusState::kUnknown;
  std::int64_t malformed_ = 0;
  HalStatus pending_status_ = HalStatus::kOk;
  char last_error_[160] = {};
};

namespace socketcan_detail {
// The start-up failure text for `call` failing with `err` on `ifname`. Exposed
// so tests can check the advice for errors this machine cannot produce.
std::string open_error_message(const std::string& ifname, const char* call, int err);
}  // namespace socketcan_detail

}  // namespace rtfuse::hal
