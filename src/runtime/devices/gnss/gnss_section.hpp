#pragma once
// [gnss]: a GNSS receiver on a serial port (UART or USB CDC-ACM), feeding the
// [[sensor]] with source = "gnss" (a navsat sensor) its fixes.
// Schema: docs/configuration.md.
#include <cstdint>

#include "runtime/config/name.hpp"

namespace rtfuse {

enum class GnssProtocolConfig : std::uint8_t { kUbx, kNmea };

struct GnssSection {
  bool enabled = false;
  Name device{"/dev/ttyACM0"};
  int baud = 115200;  // a USB CDC-ACM port ignores it; a UART needs the receiver's
  GnssProtocolConfig protocol = GnssProtocolConfig::kUbx;
  bool use_rmc = true;   // NMEA: wait for RMC in each epoch
  bool use_gst = false;  // NMEA: wait for GST (the receiver's error estimate)
  // The receiver sends an epoch this long after it (u-blox: 50-200 ms, the
  // more the higher the rate and the longer the messages): the fix is fused
  // at its epoch, through the filter's lagged-data history.
  double latency_s = 0.1;
  double silent_after_s = 2.0;  // no byte for this long: the receiver is silent
  double reopen_backoff_s = 0.5;  // first wait before reopening an unplugged receiver
  double reopen_backoff_max_s = 8.0;
};

}  // namespace rtfuse
