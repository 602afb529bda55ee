#include "runtime/fusion/standstill_status.hpp"

#include <cstdio>

namespace rtfuse {

const char* const kStandstillKeys[7] = {"blocks",        "dropped",       "rejected",     "learnt_ms",
                                        "bias_x_urad_s", "bias_y_urad_s", "bias_z_urad_s"};

int standstill_slot_count(const RuntimeConfig& cfg) noexcept {
  int n = 0;
  for (int i = 0; i < cfg.num_sensors; ++i) {
    if (cfg.sensors[static_cast<std::size_t>(i)].standstill_sensor >= 0) ++n;
  }
  return n < kMaxStandstillLearners ? n : kMaxStandstillLearners;
}

void describe_standstill(const RuntimeConfig& cfg, DeviceStatus* out) noexcept {
  const int count = standstill_slot_count(cfg);
  char buf[160];
  int k = 0;
  for (int i = 0; i < cfg.num_sensors && k < count; ++i) {
    const SensorConfig& c = cfg.sensors[static_cast<std::size_t>(i)];
    if (c.standstill_sensor < 0) continue;
    DeviceStatus& d = out[k++];
    std::snprintf(buf, sizeof buf, "gyro bias %s", qualified_sensor_name(cfg, i).c_str());
    d.name = buf;
    d.hardware_id = cfg.sensors[static_cast<std::size_t>(c.standstill_sensor)].name.c_str();
    describe_keys(d, kStandstillKeys);
  }
}

}  // namespace rtfuse
