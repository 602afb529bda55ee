#include "runtime/devices/gnss/gnss_device.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/devices/device_registry.hpp"

namespace rtfuse {

const char* const kGnssKeys[14] = {"epochs",     "fixes",   "no_fix",      "two_d", "dead_reckoning",
                                   "time_jumps", "refused", "lost_epochs", "bytes", "read_errors",
                                   "silent_events", "reopens", "satellites", "hdop_milli"};

drivers::GnssReceiverConfig gnss_driver_config(const GnssSection& g) noexcept {
  drivers::GnssReceiverConfig c;
  c.protocol = g.protocol == GnssProtocolConfig::kNmea ? drivers::GnssProtocol::kNmea : drivers::GnssProtocol::kUbx;
  c.nmea.use_rmc = g.use_rmc;
  c.nmea.use_gst = g.use_gst;
  c.silent_after_ns = sec_to_ns(g.silent_after_s);
  return c;
}

void gnss_fix_to_sample(const drivers::GnssFix& fix, TimeNs latency_ns, est::SensorSample* out) noexcept {
  const std::uint8_t sensor = out->sensor;
  *out = est::SensorSample{};
  out->sensor = sensor;
  out->kind = est::SensorKind::kNavSatFix;
  out->stamp = fix.stamp - latency_ns;
  est::NavSatFixSample& n = out->navsat;
  // The receiver's own dead reckoning has no satellite in it: fusing it
  // would feed the filter its own kind of guess back.
  const bool no_fix = fix.status == drivers::GnssStatus::kNoFix || fix.solution == drivers::GnssSolution::kDeadReckoning;
  n.status = no_fix ? std::int8_t{-1} : static_cast<std::int8_t>(fix.status);
  n.covariance_type = static_cast<std::uint8_t>(fix.covariance_type);
  n.position = {fix.latitude_deg, fix.longitude_deg, fix.has_altitude ? fix.altitude_m : 0.0};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) n.covariance(r, c) = fix.covariance_enu[r * 3 + c];
  }
  if ((fix.two_d || !fix.has_altitude) && n.covariance_type != 0) {
    // A held altitude is no measurement of it.
    n.covariance(2, 2) = std::max(n.covariance(2, 2), 1e6);
    n.covariance(0, 2) = n.covariance(2, 0) = n.covariance(1, 2) = n.covariance(2, 1) = 0.0;
  }
}

GnssDevice::GnssDevice(const DeviceBuses& buses, FusionCore& core, int device_slot)
    : core_(core),
      port_(*buses.serial),
      clock_(*buses.clock),
      sensor_(source_sensor(core.config(), "gnss")),
      slot_(device_slot) {}

std::unique_ptr<GnssDevice> GnssDevice::create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                               std::string* error) {
  if (buses.serial == nullptr || buses.clock == nullptr) {
    *error = "[gnss] is configured but the HAL has no serial port for it";
    return nullptr;
  }
  const GnssSection& g = core.config().hardware.gnss;
  std::unique_ptr<GnssDevice> d(new GnssDevice(buses, core, device_slot));
  d->latency_ns_ = sec_to_ns(g.latency_s);
  d->backoff_min_ns_ = sec_to_ns(g.reopen_backoff_s);
  d->backoff_max_ns_ = sec_to_ns(g.reopen_backoff_max_s);
  d->backoff_ns_ = d->backoff_min_ns_;
  d->receiver_ = std::make_unique<drivers::GnssReceiver>(*buses.serial, *buses.clock, gnss_driver_config(g));
  d->sample_.sensor = static_cast<std::uint8_t>(d->sensor_ < 0 ? 0 : d->sensor_);
  d->health_.store(d->scratch_);
  return d;
}

void GnssDevice::recover(TimeNs timeout_ns) noexcept {
  const TimeNs now = clock_.now();
  if (now < next_reopen_) {
    clock_.sleep_until(std::min(next_reopen_, now + timeout_ns));
    return;
  }
  if (port_.reopen()) {
    port_open_ = true;
    backoff_ns_ = backoff_min_ns_;
    ++scratch_.reopens;
  } else {
    next_reopen_ = now + backoff_ns_;
    backoff_ns_ = std::min(2 * backoff_ns_, backoff_max_ns_);
  }
}

void GnssDevice::step(TimeNs timeout_ns) noexcept {
  Health& h = scratch_;
  if (!port_open_) {
    recover(timeout_ns);
  } else {
    const int n = receiver_->poll(timeout_ns, fixes_, kFixesPerStep);
    for (int i = 0; i < n; ++i) {
      gnss_fix_to_sample(fixes_[i], latency_ns_, &sample_);
      core_.input().push_from_driver(sensor_, sample_);
      samples_.fetch_add(1, std::memory_order_acq_rel);
      h.satellites = fixes_[i].satellites;
      h.hdop = fixes_[i].hdop;
    }
    if (receiver_->health() == drivers::GnssHealth::kClosed) {
      port_open_ = false;
      next_reopen_ = clock_.now() + backoff_ns_;
    }
  }
  h.stats = receiver_->stats();
  h.state = receiver_->health();
  const char* why = port_open_ ? receiver_->last_refusal() : port_.last_error();
  if (why[0] != '\0') set_device_message(h.error, why);
  health_.store(h);
}

void GnssDevice::fill_snapshot(Snapshot& s) noexcept {
  if (slot_ < 0) return;
  Health h;
  health_.load(h);
  DeviceStatus& d = s.devices[slot_];
  const drivers::GnssReceiverStats& st = h.stats;
  set_device_values(d, kGnssKeys,
                    {st.epochs, st.epochs - st.no_fix_epochs, st.no_fix_epochs, st.two_d, st.dead_reckoning,
                     st.time_jumps, st.refused, st.lost_epochs, st.bytes, st.read_errors, st.silent_events, h.reopens,
                     h.satellites, h.hdop < 0 ? -1 : static_cast<std::int64_t>(std::lround(h.hdop * 1000.0))});
  d.state = drivers::to_string(h.state);
  d.message = h.error;
  switch (h.state) {
    case drivers::GnssHealth::kFix: d.level = DeviceLevel::kOk; break;
    case drivers::GnssHealth::kStarting: d.level = DeviceLevel::kStale; break;
    case drivers::GnssHealth::kNoFix: d.level = DeviceLevel::kWarn; break;
    case drivers::GnssHealth::kSilent:
    case drivers::GnssHealth::kClosed: d.level = DeviceLevel::kError; break;
  }
}

}  // namespace rtfuse
