#pragma once
// A serial byte stream (UART, USB CDC-ACM) as a GNSS receiver speaks it:
// UBX and NMEA 0183 arrive as bytes with no record boundaries, so framing
// is the driver's job; the port only moves bytes and says when it saw them.
#include <cstdint>

#include "core/time.hpp"
#include "hal/status.hpp"

namespace rtfuse::hal {

class SerialPort {
 public:
  virtual ~SerialPort() = default;
  // Up to max bytes into out. timeout_ns 0: return at once (kWouldBlock if
  // nothing is queued); > 0: wait at most that long for the first byte, then
  // take what is queued without waiting. *stamp: CLOCK_MONOTONIC ns when the
  // bytes were seen (as near to their reception as the backend can observe).
  // Returns the byte count; 0 with *status saying why.
  virtual int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept = 0;
  // All of size bytes, or an error (receiver configuration messages).
  virtual HalStatus write(const std::uint8_t* data, int size) noexcept = 0;
  // errno text of the last failure (never allocates to read).
  virtual const char* last_error() const noexcept = 0;
  // After kClosed (the device went away): open it again. True when it is
  // back; false leaves it closed with last_error() saying why. May allocate
  // (a re-initialisation after a device loss is outside the RT rules).
  virtual bool reopen() noexcept = 0;
};

}  // namespace rtfuse::hal
