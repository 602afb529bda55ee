#pragma once
// The gyro bias learners' diagnostics slots (estimation/standstill_gyro_bias):
// one per imu sensor with standstill_from, after the navsat transforms'
// (they are the fusion core's, not a device's).
#include "runtime/config/config.hpp"
#include "runtime/fusion/device_status.hpp"

namespace rtfuse {

// Blocks learnt, dropped by a start, input refused; seconds learnt (ms,
// capped at the time constant); the bias, urad/s per axis of the IMU.
extern const char* const kStandstillKeys[7];

int standstill_slot_count(const RuntimeConfig& cfg) noexcept;
// Names, ids and keys of out[0 .. standstill_slot_count).
void describe_standstill(const RuntimeConfig& cfg, DeviceStatus* out) noexcept;

}  // namespace rtfuse
