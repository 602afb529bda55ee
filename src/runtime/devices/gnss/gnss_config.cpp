#include "runtime/devices/gnss/gnss_config.hpp"

#include <string>
#include <string_view>

#include "hal/linux/termios_serial_port.hpp"
#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

void read_gnss(const Section& s, GnssSection& g) {
  s.reject_unknown({"device", "baud", "protocol", "use_rmc", "use_gst", "latency", "silent_after", "reopen_backoff",
                    "reopen_backoff_max"});
  g.enabled = true;
  s.read_name("device", g.device);
  read_int(s, "baud", g.baud, 1, 4'000'000);
  if (!hal::TermiosSerialPort::supports(g.baud)) {
    s.value_error("baud", "must be one of " + hal::TermiosSerialPort::supported_bauds() + ", got " +
                              std::to_string(g.baud));
  }
  std::string protocol;
  if (s.read("protocol", protocol)) {
    if (protocol == "ubx") {
      g.protocol = GnssProtocolConfig::kUbx;
    } else if (protocol == "nmea") {
      g.protocol = GnssProtocolConfig::kNmea;
    } else {
      s.value_error("protocol", "must be ubx (u-blox NAV-PVT) or nmea (GGA/RMC/GST), got " + in_quotes(protocol));
    }
  }
  s.read("use_rmc", g.use_rmc);
  s.read("use_gst", g.use_gst);
  if (g.protocol == GnssProtocolConfig::kUbx) {
    for (std::string_view k : {"use_rmc", "use_gst"}) {
      if (s.has(k)) s.key_error(k, "only valid with protocol = \"nmea\"");
    }
  }
  read_number(s, "latency", g.latency_s, [](double v) { return v >= 0 && v <= 2.0; }, "must be >= 0 and <= 2 s");
  read_number(s, "silent_after", g.silent_after_s, [](double v) { return v >= 0.2 && v <= 60.0; },
              "must be >= 0.2 and <= 60 s");
  read_number(s, "reopen_backoff", g.reopen_backoff_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "reopen_backoff_max", g.reopen_backoff_max_s, positive_finite, "must be > 0 s and finite");
  if (g.reopen_backoff_max_s < g.reopen_backoff_s) {
    s.value_error("reopen_backoff_max", "must be >= reopen_backoff");
  }
}

}  // namespace

void read_gnss_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* gnss = section_table(root, "gnss");
  if (gnss) read_gnss(Section(gnss, "gnss", root.diag()), cfg.hardware.gnss);
}

}  // namespace rtfuse::config
