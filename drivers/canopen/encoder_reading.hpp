#pragma once
// What the CANopen encoder master hands the rest of the system: one reading
// per node per SYNC, grouped in sample sets, plus counters for diagnostics.
#include <cstdint>

#include "core/time.hpp"
#include "hal/can_bus.hpp"

namespace rtfuse::drivers {

constexpr int kMaxEncoderNodes = 8;

// Why a reading is (in)valid. Only kOk readings are valid; the others say
// which fault excludes the node. Ordered by precedence: when several apply,
// the first in this list is reported.
enum class EncoderHealth : std::uint8_t {
  kOk,
  kBusOff,      // the controller is (or was, until this node's next TPDO) off the bus
  kSilent,      // heartbeat timeout or tpdo_timeout_syncs SYNCs without a TPDO
  kNotStarted,  // no TPDO received yet
  kNoSample,    // no TPDO for this SYNC (not yet silent)
  kEmcy,        // an EMCY error is active (until the node sends error reset 0x0000 or reboots)
  kStuck,       // counter frozen while other wheels move
  kJump,        // this sample moved faster than max_counts_per_s: rejected
};

const char* to_string(EncoderHealth health) noexcept;

struct EncoderReading {
  bool valid = false;
  // Continuous position in counts (wrap-around removed). Kept at the last
  // accepted value when the reading is invalid.
  std::int64_t counts = 0;
  // Time the SYNC that sampled this position was sent (CiA 301 synchronous
  // TPDO: the device latches its position on SYNC reception and transmits
  // afterwards, so the receive time would be late by the bus latency).
  TimeNs stamp = 0;
  std::int64_t sample_seq = 0;  // that SYNC's sequence number (1, 2, ...)
  // Incremented whenever continuity of `counts` with the previous samples is
  // not known (first sample after silence or bus-off, a rejected jump): a
  // consumer differencing counts must only difference within one segment.
  std::uint32_t segment = 0;
  EncoderHealth health = EncoderHealth::kNotStarted;
};

// Every configured node's reading for one SYNC, in configuration order.
struct EncoderSampleSet {
  std::int64_t seq = 0;
  TimeNs stamp = 0;
  int node_count = 0;
  int valid_count = 0;
  EncoderReading readings[kMaxEncoderNodes];
};

struct EncoderNodeStats {
  std::int64_t tpdos = 0;
  std::int64_t heartbeats = 0;
  std::int64_t boot_ups = 0;
  std::uint8_t last_nmt_state = 0xFF;  // heartbeat byte; 0xFF: none seen yet
  std::int64_t emcys = 0;              // every EMCY, error resets included
  std::int64_t emcy_resets = 0;
  std::uint16_t last_emcy_code = 0;
  std::uint8_t last_emcy_register = 0;
  std::int64_t missed_syncs = 0;  // SYNCs sent that this node did not answer
  std::int64_t silent_events = 0;
  std::int64_t stuck_events = 0;
  std::int64_t jump_events = 0;
  std::int64_t recoveries = 0;  // back to kOk after silent, bus-off, EMCY, stuck or a jump
  std::int64_t nmt_starts = 0;  // NMT start commands sent to this node
};

struct CanopenBusStats {
  std::int64_t syncs_sent = 0;
  std::int64_t nmt_sent = 0;
  std::int64_t send_failures = 0;
  std::int64_t receive_errors = 0;     // receive() failures other than "nothing queued"
  std::int64_t frames_received = 0;
  std::int64_t malformed_frames = 0;   // DLC > 8, or wrong DLC for the object (TPDO mapping, heartbeat, EMCY)
  std::int64_t unexpected_cob_ids = 0; // not an object of a configured node (extended ids included)
  std::int64_t rtr_frames = 0;
  std::int64_t error_frames = 0;
  std::int64_t bus_off_events = 0;
  std::int64_t stale_tpdos = 0;        // no SYNC to attribute it to, or a second one for the same SYNC
  std::int64_t late_tpdos = 0;         // arrived after its SYNC's set was closed (tracked, not in a set)
  std::int64_t complete_sets = 0;
  std::int64_t incomplete_sets = 0;    // a node that is not excluded missed the SYNC
  std::int64_t rx_limit_hits = 0;      // poll() took max_frames_per_poll frames; the rest waits for the next
  hal::CanBusState bus_state = hal::CanBusState::kUnknown;
  bool bus_off = false;
};

}  // namespace rtfuse::drivers
