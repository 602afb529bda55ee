#pragma once
// The navsat transforms' diagnostics slots: one per navsat sensor, after the
// devices' slots (they are the fusion core's, not a device's).
#include "runtime/config/config.hpp"
#include "runtime/fusion/device_status.hpp"

namespace rtfuse {

// The transform's refusals by reason (est::NavsatStats).
extern const char* const kNavsatKeys[7];

int navsat_slot_count(const RuntimeConfig& cfg) noexcept;
// Names, ids and keys of out[0 .. navsat_slot_count).
void describe_navsat(const RuntimeConfig& cfg, DeviceStatus* out) noexcept;

}  // namespace rtfuse
