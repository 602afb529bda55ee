#include "runtime/fusion/navsat_status.hpp"

#include <cstdio>

namespace rtfuse {

const char* const kNavsatKeys[7] = {"accepted",           "no_fix", "invalid_position", "invalid_covariance",
                                    "waiting_for_heading", "jumps",  "reanchors"};

int navsat_slot_count(const RuntimeConfig& cfg) noexcept {
  int n = 0;
  for (int i = 0; i < cfg.num_sensors; ++i) {
    if (cfg.sensors[static_cast<std::size_t>(i)].params.kind == est::SensorKind::kNavSatFix) ++n;
  }
  // The loader refuses more.
  return n < kMaxNavsatSensors ? n : kMaxNavsatSensors;
}

void describe_navsat(const RuntimeConfig& cfg, DeviceStatus* out) noexcept {
  const int count = navsat_slot_count(cfg);
  char buf[160];
  int k = 0;
  for (int i = 0; i < cfg.num_sensors && k < count; ++i) {
    const SensorConfig& c = cfg.sensors[static_cast<std::size_t>(i)];
    if (c.params.kind != est::SensorKind::kNavSatFix) continue;
    DeviceStatus& d = out[k++];
    std::snprintf(buf, sizeof buf, "navsat %s", qualified_sensor_name(cfg, i).c_str());
    d.name = buf;
    d.hardware_id = c.channel.empty() ? c.name.c_str() : c.channel.c_str();
    describe_keys(d, kNavsatKeys);
  }
}

}  // namespace rtfuse
