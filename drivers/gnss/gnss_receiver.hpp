#pragma once
// A GNSS receiver on a serial port: bytes in, fixes out. The protocol is
// the receiver's configuration (u-blox speaks UBX, anything else NMEA
// 0183); bytes of the other protocol on the same port are skipped and
// counted, not errors. Health for diagnostics, with the faults receivers
// have: no fix (it talks, it has no position), silence (unplugged, a dead
// receiver, the wrong baud rate — a wrong baud rate also shows as many
// bytes and no frame), the port gone, and the epoch running backwards
// (a receiver that restarted with a wrong clock).
//
// No threads and no allocation: the caller (the runtime's GNSS device, on a
// thread of its own) calls poll() in a loop.
#include <cstdint>

#include "drivers/gnss/gnss_fix.hpp"
#include "drivers/gnss/nmea_fix_assembler.hpp"
#include "drivers/gnss/nmea_framer.hpp"
#include "drivers/gnss/ubx_framer.hpp"
#include "hal/clock.hpp"
#include "hal/serial_port.hpp"

namespace rtfuse::drivers {

enum class GnssProtocol : std::uint8_t { kUbx, kNmea };

struct GnssReceiverConfig {
  GnssProtocol protocol = GnssProtocol::kUbx;
  NmeaFixConfig nmea;
  // No byte for this long: silent. A receiver at 1 Hz sends every second.
  TimeNs silent_after_ns = 2'000'000'000;
};

enum class GnssHealth : std::uint8_t {
  kStarting,  // nothing received yet
  kFix,       // the last epoch had a fix
  kNoFix,     // the receiver talks but has no position
  kSilent,    // no byte for silent_after_ns
  kClosed,    // the port went away (unplugged); the device reopens it
};

const char* to_string(GnssHealth h) noexcept;

struct GnssReceiverStats {
  std::int64_t bytes = 0;
  std::int64_t epochs = 0;         // fixes handed out, with or without a position
  std::int64_t no_fix_epochs = 0;  // status kNoFix among them
  std::int64_t dead_reckoning = 0; // the receiver extrapolating (alone or blended)
  std::int64_t two_d = 0;
  std::int64_t refused = 0;        // a NAV-PVT whose fields are impossible
  std::int64_t time_jumps = 0;     // an epoch before the previous one (not across midnight)
  std::int64_t silent_events = 0;
  std::int64_t read_errors = 0;    // anything but a timeout, counted per call
  std::int64_t lost_epochs = 0;    // more in one poll() than the caller had room for
};

class GnssReceiver {
 public:
  GnssReceiver(hal::SerialPort& port, hal::Clock& clock, const GnssReceiverConfig& config) noexcept;

  // Waits up to timeout_ns for bytes, frames what came; up to max fixes
  // into out (a burst of several epochs after a stall gives several).
  // Returns how many.
  int poll(TimeNs timeout_ns, GnssFix* out, int max) noexcept;

  GnssHealth health() const noexcept { return health_; }
  const GnssReceiverStats& stats() const noexcept { return stats_; }
  const NmeaFramerStats& nmea_framer() const noexcept { return nmea_.stats(); }
  const NmeaFixStats& nmea_fixes() const noexcept { return assembler_.stats(); }
  const UbxFramerStats& ubx_framer() const noexcept { return ubx_.stats(); }
  // Why the last NAV-PVT or NMEA sentence was refused, or "".
  const char* last_refusal() const noexcept { return last_refusal_; }
  TimeNs last_byte() const noexcept { return last_byte_; }

 private:
  // Counts the epoch, follows its health, and copies it out.
  void take(const GnssFix& fix, GnssFix* out) noexcept;

  hal::SerialPort& port_;
  hal::Clock& clock_;
  GnssReceiverConfig config_;
  NmeaFramer nmea_;
  NmeaFixAssembler assembler_;
  UbxFramer ubx_;
  GnssHealth health_ = GnssHealth::kStarting;
  GnssReceiverStats stats_;
  TimeNs started_ = 0;
  TimeNs last_byte_ = -1;
  std::int64_t last_epoch_ms_ = -1;
  const char* last_refusal_ = "";
  std::uint8_t buf_[512] = {};
};

}  // namespace rtfuse::drivers
