#pragma once
// Settings of the CANopen encoder master: plain values, filled by the
// runtime's TOML loader and checked once by validate_config() before use.
#include <array>
#include <cstdint>
#include <string>

#include "core/time.hpp"
#include "drivers/canopen/cia301.hpp"
#include "drivers/canopen/encoder_reading.hpp"

namespace rtfuse::drivers {

// Where the position value sits in the node's synchronous TPDO. The default
// is CiA 406's position value (object 0x6004) mapped alone into TPDO1.
struct TpdoMapping {
  std::uint32_t cob_id = 0;  // 0: 0x180 + node_id (TPDO1 of the predefined connection set)
  std::uint8_t byte_offset = 0;
  std::uint8_t width_bits = 32;  // 8, 16, 24 or 32
  bool is_signed = false;
};

struct EncoderNodeConfig {
  std::uint8_t node_id = 0;  // 1..127
  TpdoMapping tpdo;
  // Fastest physically possible count rate of this encoder; 0: the global
  // CanopenEncodersConfig::max_counts_per_s.
  double max_counts_per_s = 0.0;
};

struct CanopenEncodersConfig {
  int node_count = 0;
  std::array<EncoderNodeConfig, kMaxEncoderNodes> nodes{};

  std::uint32_t sync_cob_id = cia301::kDefaultSyncCobId;
  // Heartbeat consumer time (CiA 301: supervision starts with the first
  // heartbeat received). 0 disables heartbeat supervision.
  TimeNs heartbeat_timeout_ns = 500'000'000;
  // SYNCs in a row without a TPDO before the node counts as silent.
  int tpdo_timeout_syncs = 5;
  // Jump detection: a sample moving more than this * dt (+1 count of
  // quantisation) since the previous one is rejected. 0 disables it.
  double max_counts_per_s = 0.0;
  // Stuck detection: the counter did not change for stuck_time_ns while
  // another node moved by more than stuck_min_counts. stuck_time_ns 0 disables.
  TimeNs stuck_time_ns = 1'000'000'000;
  std::int64_t stuck_min_counts = 500;
  // Least time between two NMT start commands to the same node when its
  // heartbeat says boot-up, pre-operational or stopped.
  TimeNs nmt_restart_interval_ns = 200'000'000;
  // Bound on the frames one poll() takes from the bus.
  int max_frames_per_poll = 64;
};

// The COB-ID the node's TPDO really uses (the default resolved).
std::uint32_t effective_tpdo_cob_id(const EncoderNodeConfig& node) noexcept;

// True when the config can be used; otherwise *error names the field, the
// value and the likely fix.
bool validate_config(const CanopenEncodersConfig& config, std::string* error);

}  // namespace rtfuse::drivers
