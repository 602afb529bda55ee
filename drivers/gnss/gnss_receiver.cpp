#include "drivers/gnss/gnss_receiver.hpp"

#include "drivers/gnss/ubx_nav_pvt.hpp"

namespace rtfuse::drivers {

const char* to_string(GnssHealth h) noexcept {
  switch (h) {
    case GnssHealth::kStarting: return "starting";
    case GnssHealth::kFix: return "fix";
    case GnssHealth::kNoFix: return "no fix";
    case GnssHealth::kSilent: return "silent";
    case GnssHealth::kClosed: return "closed";
  }
  return "?";
}

GnssReceiver::GnssReceiver(hal::SerialPort& port, hal::Clock& clock, const GnssReceiverConfig& config) noexcept
    : port_(port), clock_(clock), config_(config), assembler_(config.nmea), started_(clock.now()) {}

void GnssReceiver::take(const GnssFix& fix, GnssFix* out) noexcept {
  ++stats_.epochs;
  if (fix.status == GnssStatus::kNoFix) ++stats_.no_fix_epochs;
  if (fix.dead_reckoning) ++stats_.dead_reckoning;
  if (fix.two_d) ++stats_.two_d;
  if (fix.utc_ms_of_day >= 0) {
    // Across midnight the time of day starts again; anything else going back
    // is the receiver's clock.
    const bool midnight = last_epoch_ms_ > 86'400'000 - 3'600'000 && fix.utc_ms_of_day < 3'600'000;
    if (last_epoch_ms_ >= 0 && fix.utc_ms_of_day < last_epoch_ms_ && !midnight) ++stats_.time_jumps;
    last_epoch_ms_ = fix.utc_ms_of_day;
  }
  health_ = fix.status == GnssStatus::kNoFix ? GnssHealth::kNoFix : GnssHealth::kFix;
  *out = fix;
}

int GnssReceiver::poll(TimeNs timeout_ns, GnssFix* out, int max) noexcept {
  TimeNs stamp = 0;
  hal::HalStatus status = hal::HalStatus::kOk;
  const int n = port_.read(buf_, static_cast<int>(sizeof buf_), timeout_ns, &stamp, &status);
  int fixes = 0;
  if (n > 0) {
    stats_.bytes += n;
    last_byte_ = stamp;
    if (health_ == GnssHealth::kSilent || health_ == GnssHealth::kClosed) health_ = GnssHealth::kStarting;
    for (int i = 0; i < n; ++i) {
      GnssFix fix;
      if (config_.protocol == GnssProtocol::kNmea) {
        NmeaFramer::Sentence s;
        if (nmea_.push(buf_[i], stamp, &s) && assembler_.add(s, &fix)) {
          if (fixes < max) {
            take(fix, out + fixes++);
          } else {
            ++stats_.lost_epochs;
          }
        }
        if (assembler_.stats().malformed > 0) last_refusal_ = assembler_.last_malformed();
      } else {
        UbxFramer::Frame f;
        if (!ubx_.push(buf_[i], stamp, &f) || f.msg_class != kUbxClassNav || f.msg_id != kUbxIdNavPvt) continue;
        const char* why = "";
        if (!decode_nav_pvt(f.payload, f.length, f.stamp, &fix, &why)) {
          ++stats_.refused;
          last_refusal_ = why;
          continue;
        }
        if (fixes < max) {
          take(fix, out + fixes++);
        } else {
          ++stats_.lost_epochs;
        }
      }
    }
    return fixes;
  }
  if (status == hal::HalStatus::kClosed) {
    health_ = GnssHealth::kClosed;
    return 0;
  }
  // The port answers again (reopened): the receiver has yet to speak.
  if (health_ == GnssHealth::kClosed) health_ = GnssHealth::kStarting;
  if (status != hal::HalStatus::kTimeout && status != hal::HalStatus::kWouldBlock) {
    ++stats_.read_errors;
  }
  const TimeNs since = last_byte_ >= 0 ? last_byte_ : started_;
  if (health_ != GnssHealth::kClosed && health_ != GnssHealth::kSilent &&
      clock_.now() - since >= config_.silent_after_ns) {
    health_ = GnssHealth::kSilent;
    ++stats_.silent_events;
  }
  return 0;
}

}  // namespace rtfuse::drivers
