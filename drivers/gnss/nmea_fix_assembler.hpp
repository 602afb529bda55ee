#pragma once
// A fix from the NMEA sentences of one epoch. Receivers send an epoch as a
// burst of sentences sharing one UTC time (RMC, GGA, GSA, GSV, GST... in a
// receiver's own order); the fix is complete when every sentence the
// receiver was configured to send for it has arrived: GGA always, RMC and
// GST if asked. A sentence of a newer epoch closes an incomplete one: it is
// emitted with what it had (counted) if it has its GGA, dropped otherwise.
//
// Covariance: the receiver's own GST sigmas when there are all three;
// otherwise nmea_navsat_driver's model, so a robot moving from ROS keeps its
// covariances: sigma = HDOP x epe[GGA quality] horizontally, twice that
// vertically (approximated); without HDOP, unknown.
#include <cstdint>

#include "drivers/gnss/gnss_fix.hpp"
#include "drivers/gnss/nmea_framer.hpp"
#include "drivers/gnss/nmea_sentences.hpp"

namespace rtfuse::drivers {

struct NmeaFixConfig {
  bool use_rmc = true;   // wait for RMC: validity, mode, speed and course
  bool use_gst = false;  // wait for GST: the receiver's error estimate
  // Per GGA quality 0..9, in m (nmea_navsat_driver's epe_quality defaults).
  double epe_m[10] = {1e6, 4.0, 0.1, 4.0, 0.02, 4.0, 1e6, 1e6, 1e6, 3.0};
};

struct NmeaFixStats {
  std::int64_t fixes = 0;              // epochs emitted (with or without a position)
  std::int64_t incomplete_epochs = 0;  // emitted without every configured sentence
  std::int64_t dropped_epochs = 0;     // closed without a GGA
  std::int64_t malformed = 0;          // a GGA, RMC or GST with a bad field
  std::int64_t other_sentences = 0;    // types a fix does not use (GSA, GSV, VTG, proprietary)
};

class NmeaFixAssembler {
 public:
  explicit NmeaFixAssembler(const NmeaFixConfig& config) : config_(config) {}

  // One sentence from the framer; true when it completed (or closed) an
  // epoch, then in *fix.
  bool add(const NmeaFramer::Sentence& sentence, GnssFix* fix) noexcept;

  const NmeaFixStats& stats() const noexcept { return stats_; }
  // The field of the last malformed sentence ("GGA latitude"), or "".
  const char* last_malformed() const noexcept { return last_malformed_; }

 private:
  struct Pending {
    bool open = false;
    std::int64_t utc_ms = -1;
    TimeNs stamp = 0;
    bool has_gga = false, has_rmc = false, has_gst = false;
    NmeaGga gga;
    NmeaRmc rmc;
    NmeaGst gst;
  };
  bool complete() const noexcept;
  void build(GnssFix* fix) const noexcept;
  void open(std::int64_t utc_ms, TimeNs stamp) noexcept;

  NmeaFixConfig config_;
  Pending pending_;
  NmeaFields fields_;
  NmeaFixStats stats_;
  const char* last_malformed_ = "";
};

}  // namespace rtfuse::drivers
