#include "drivers/canopen/canopen_encoders.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "drivers/canopen/position_unwrap.hpp"
#include "hal/status.hpp"

namespace rtfuse::drivers {

// Per-node protocol and supervision state; everything fixed-size.
struct CanopenEncoders::Node {
  EncoderNodeConfig cfg;
  std::uint32_t tpdo_id = 0;
  int bits = 32;
  int bytes = 4;
  double max_counts_per_s = 0.0;

  // Unwrap.
  bool has_raw = false;
  bool resync = false;  // continuity lost (silence, bus-off): next sample starts a segment
  std::uint64_t last_raw = 0;
  std::int64_t counts = 0;
  std::uint32_t segment = 0;
  std::int64_t last_seq = 0;
  TimeNs last_time = 0;

  // What arrived since the last set closed.
  std::int64_t reported_seq = 0;
  bool reported_jump = false;
  std::int64_t pending_step = 0;
  int pending_samples = 0;  // accepted samples whose step is known

  // Supervision.
  int missed = 0;
  bool silent = false;
  bool hb_seen = false;
  bool hb_timed_out = false;
  TimeNs last_hb = 0;
  bool emcy_active = false;
  bool bus_off = false;
  bool stuck = false;
  TimeNs still_ns = 0;       // time spent unchanged while another node moved
  TimeNs prev_info_time = 0;
  std::array<std::int64_t, kMaxEncoderNodes> others_moved{};

  // NMT.
  bool start_sent = false;
  bool start_wanted = false;
  TimeNs last_start = 0;

  EncoderReading reading;
  EncoderNodeStats stats;
  char error[96] = {};  // the last fault in words (node_error())
};

namespace {

std::int64_t abs64(std::int64_t v) { return v < 0 ? -v : v; }

bool excluded(EncoderHealth h) {
  return h == EncoderHealth::kBusOff || h == EncoderHealth::kSilent || h == EncoderHealth::kEmcy ||
         h == EncoderHealth::kStuck || h == EncoderHealth::kJump;
}

}  // namespace

std::unique_ptr<CanopenEncoders> CanopenEncoders::create(hal::CanBus& bus, const CanopenEncodersConfig& config,
                                                         std::string* error) {
  if (!validate_config(config, error)) return nullptr;
  return std::unique_ptr<CanopenEncoders>(new CanopenEncoders(bus, config));
}

CanopenEncoders::CanopenEncoders(hal::CanBus& bus, const CanopenEncodersConfig& config)
    : bus_(bus), config_(config), nodes_(new Node[kMaxEncoderNodes]) {
  const double global_max = config_.max_counts_per_s;
  for (int i = 0; i < config_.node_count; ++i) {
    Node& n = nodes_[i];
    n.cfg = config_.nodes[static_cast<std::size_t>(i)];
    n.tpdo_id = effective_tpdo_cob_id(n.cfg);
    n.bits = n.cfg.tpdo.width_bits;
    n.bytes = n.bits / 8;
    n.max_counts_per_s = n.cfg.max_counts_per_s > 0.0 ? n.cfg.max_counts_per_s : global_max;
    const std::uint32_t ids[3] = {n.tpdo_id, cia301::kHeartbeatBase + n.cfg.node_id, cia301::kEmcyBase + n.cfg.node_id};
    const Object objs[3] = {Object::kTpdo, Object::kHeartbeat, Object::kEmcy};
    for (int k = 0; k < 3; ++k) {
      owner_[ids[k]] = static_cast<std::uint8_t>(i);
      object_[ids[k]] = objs[k];
    }
  }
  last_set_.node_count = config_.node_count;
}

CanopenEncoders::~CanopenEncoders() = default;

const EncoderReading& CanopenEncoders::reading(int node) const noexcept {
  static const EncoderReading kNone{};
  return node >= 0 && node < config_.node_count ? nodes_[node].reading : kNone;
}

const EncoderNodeStats& CanopenEncoders::node_stats(int node) const noexcept {
  static const EncoderNodeStats kNone{};
  return node >= 0 && node < config_.node_count ? nodes_[node].stats : kNone;
}

const char* CanopenEncoders::node_error(int node) const noexcept {
  return node >= 0 && node < config_.node_count ? nodes_[node].error : "";
}

void CanopenEncoders::set_node_error(Node& node, const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(node.error, sizeof node.error, fmt, ap);
  va_end(ap);
}

void CanopenEncoders::malformed(const hal::CanFrame& frame) noexcept {
  ++bus_stats_.malformed_frames;
  std::snprintf(last_error_, sizeof last_error_, "malformed frame COB-ID 0x%03X with %d data bytes; dropped",
                static_cast<unsigned>(frame.id), static_cast<int>(frame.dlc));
}

void CanopenEncoders::set_error(const char* what, std::uint32_t cob_id) noexcept {
  std::snprintf(last_error_, sizeof last_error_, "%s (COB-ID 0x%03X) refused by the bus: %s", what,
                static_cast<unsigned>(cob_id), bus_.last_error());
}

bool CanopenEncoders::send_nmt_start(Node& node, TimeNs now) noexcept {
  hal::CanFrame f;
  f.id = cia301::kNmtCobId;
  f.dlc = 2;
  f.data[0] = cia301::kNmtStartRemoteNode;
  f.data[1] = node.cfg.node_id;
  if (bus_.send(f) != hal::HalStatus::kOk) {
    ++bus_stats_.send_failures;
    char what[40];
    std::snprintf(what, sizeof what, "NMT start of node %d", node.cfg.node_id);
    set_error(what, f.id);
    return false;
  }
  ++bus_stats_.nmt_sent;
  ++node.stats.nmt_starts;
  node.start_sent = true;
  node.start_wanted = false;
  node.last_start = now;
  return true;
}

bool CanopenEncoders::start(TimeNs now) noexcept {
  bool ok = true;
  for (int i = 0; i < config_.node_count; ++i) ok = send_nmt_start(nodes_[i], now) && ok;
  return ok;
}

void CanopenEncoders::poll(TimeNs now) noexcept {
  int budget = config_.max_frames_per_poll;
  while (budget > 0) {
    hal::HalStatus st = hal::HalStatus::kOk;
    const int n = bus_.receive(rx_.data(), std::min(budget, kRxBatch), 0, &st);
    if (n <= 0) {
      if (st != hal::HalStatus::kWouldBlock && st != hal::HalStatus::kTimeout && st != hal::HalStatus::kOk) {
        ++bus_stats_.receive_errors;
        std::snprintf(last_error_, sizeof last_error_, "CAN receive failed (%s): %s", hal::to_string(st),
                      bus_.last_error());
      }
      break;
    }
    for (int k = 0; k < n; ++k) process(rx_[static_cast<std::size_t>(k)]);
    budget -= n;
    if (budget == 0) ++bus_stats_.rx_limit_hits;
  }

  supervise_bus(now);
  supervise_heartbeats(now);
  if (sync_seq_ > closed_seq_) close_set(syncs_[static_cast<std::size_t>(sync_seq_ % kSyncHistory)]);
  if (!bus_off_) {
    for (int i = 0; i < config_.node_count; ++i) {
      Node& node = nodes_[i];
      if (node.start_wanted && (!node.start_sent || now - node.last_start >= config_.nmt_restart_interval_ns)) {
        send_nmt_start(node, now);
      }
    }
  }
  send_sync(now);
}

void CanopenEncoders::send_sync(TimeNs now) noexcept {
  hal::CanFrame f;
  f.id = config_.sync_cob_id;
  f.dlc = 0;
  if (bus_.send(f) != hal::HalStatus::kOk) {
    ++bus_stats_.send_failures;
    set_error("SYNC", f.id);
    return;
  }
  ++sync_seq_;
  syncs_[static_cast<std::size_t>(sync_seq_ % kSyncHistory)] = SyncRecord{sync_seq_, now};
  ++bus_stats_.syncs_sent;
}

bool CanopenEncoders::find_sync(TimeNs stamp, SyncRecord* out) const noexcept {
  const std::int64_t kept = std::min<std::int64_t>(sync_seq_, kSyncHistory);
  for (std::int64_t k = 0; k < kept; ++k) {
    const SyncRecord& r = syncs_[static_cast<std::size_t>((sync_seq_ - k) % kSyncHistory)];
    if (r.time <= stamp) {
      *out = r;
      return true;
    }
  }
  return false;
}

void CanopenEncoders::process(const hal::CanFrame& frame) noexcept {
  ++bus_stats_.frames_received;
  if (frame.error) {
    on_error_frame(frame);
    return;
  }
  if (frame.dlc > 8) {
    malformed(frame);
    return;
  }
  if (frame.rtr) {
    ++bus_stats_.rtr_frames;
    return;
  }
  // A controller in bus-off receives nothing: a data frame after the bus-off
  // error frame means it is back on the bus.
  if (bus_off_by_frame_ && frame.stamp > bus_off_frame_stamp_) bus_off_by_frame_ = false;
  if (frame.extended || frame.id > cia301::kMaxStandardId) {
    ++bus_stats_.unexpected_cob_ids;
    return;
  }
  Node& node = nodes_[owner_[frame.id]];
  switch (object_[frame.id]) {
    case Object::kTpdo: on_tpdo(node, frame); break;
    case Object::kHeartbeat: on_heartbeat(node, frame); break;
    case Object::kEmcy: on_emcy(node, frame); break;
    case Object::kNone: ++bus_stats_.unexpected_cob_ids; break;
  }
}

void CanopenEncoders::on_error_frame(const hal::CanFrame& frame) noexcept {
  ++bus_stats_.error_frames;
  if ((frame.id & cia301::kCanErrRestarted) != 0) bus_off_by_frame_ = false;
  // Checked last, as the HAL does: bus-off with anything else stays bus-off.
  if ((frame.id & cia301::kCanErrBusOff) != 0) {
    bus_off_by_frame_ = true;
    bus_off_frame_stamp_ = frame.stamp;
  }
}

void CanopenEncoders::on_tpdo(Node& node, const hal::CanFrame& frame) noexcept {
  if (frame.dlc < node.cfg.tpdo.byte_offset + node.bytes) {
    malformed(frame);
    return;
  }
  SyncRecord sync;
  if (!find_sync(frame.stamp, &sync) || sync.seq <= node.last_seq) {
    ++bus_stats_.stale_tpdos;
    return;
  }
  ++node.stats.tpdos;
  if (sync.seq <= closed_seq_) ++bus_stats_.late_tpdos;
  if (node.bus_off && !bus_off_ && sync.seq > bus_back_seq_) node.bus_off = false;

  const std::uint64_t raw = read_le(frame, node.cfg.tpdo.byte_offset, node.bytes);
  bool jumped = false;
  bool step_known = false;
  std::int64_t step = 0;
  if (!node.has_raw || node.resync) {
    if (!node.has_raw) {
      node.counts = position_from_raw(raw, node.bits, node.cfg.tpdo.is_signed);
    } else {
      // Best guess across the gap; the new segment tells consumers not to trust it.
      node.counts += wrapped_delta(raw, node.last_raw, node.bits);
      ++node.segment;
    }
    node.has_raw = true;
    node.resync = false;
    node.still_ns = 0;
    node.others_moved.fill(0);
    node.prev_info_time = sync.time;
  } else {
    step = wrapped_delta(raw, node.last_raw, node.bits);
    const double dt_s = ns_to_sec(sync.time - node.last_time);
    if (node.max_counts_per_s > 0.0 &&
        static_cast<double>(abs64(step)) > node.max_counts_per_s * dt_s + 1.0) {
      // Re-base on the new value so a permanent offset costs one sample.
      // Integers only: the loop formats no floating point (glibc's %f may
      // take a heap buffer for large values).
      set_node_error(node, "node %d: position jumped %lld counts in one SYNC, faster than %lld counts/s; rejected",
                     node.cfg.node_id, static_cast<long long>(step),
                     static_cast<long long>(std::llround(node.max_counts_per_s)));
      jumped = true;
      step = 0;
      ++node.segment;
      ++node.stats.jump_events;
    } else {
      node.counts += step;
      step_known = true;
    }
  }
  node.last_raw = raw;
  node.last_seq = sync.seq;
  node.last_time = sync.time;
  node.reported_seq = sync.seq;
  node.reported_jump = jumped;
  if (step_known) {
    node.pending_step += step;
    ++node.pending_samples;
  }
}

void CanopenEncoders::on_heartbeat(Node& node, const hal::CanFrame& frame) noexcept {
  if (frame.dlc != cia301::kHeartbeatDlc) {
    malformed(frame);
    return;
  }
  const std::uint8_t state = frame.data[0] & cia301::kStateMask;
  ++node.stats.heartbeats;
  node.stats.last_nmt_state = state;
  node.hb_seen = true;
  node.last_hb = std::max(node.last_hb, frame.stamp);
  switch (state) {
    case cia301::kStateBootUp:
      ++node.stats.boot_ups;
      node.emcy_active = false;  // a reset clears the device's errors
      [[fallthrough]];
    case cia301::kStateStopped:
    case cia301::kStatePreOperational:
      // Only news after our last start counts: an old frame still queued when
      // the start went out says nothing about the state since.
      if (!node.start_sent || frame.stamp > node.last_start) node.start_wanted = true;
      break;
    case cia301::kStateOperational: node.start_wanted = false; break;
    default: break;
  }
}

void CanopenEncoders::on_emcy(Node& node, const hal::CanFrame& frame) noexcept {
  if (frame.dlc != cia301::kEmcyDlc) {
    malformed(frame);
    return;
  }
  const auto code = static_cast<std::uint16_t>(frame.data[0] | (frame.data[1] << 8));
  ++node.stats.emcys;
  node.stats.last_emcy_code = code;
  node.stats.last_emcy_register = frame.data[2];
  if (code == cia301::kEmcyErrorReset) {
    ++node.stats.emcy_resets;
    node.emcy_active = false;
  } else {
    node.emcy_active = true;
    set_node_error(node, "node %d: EMCY error code 0x%04X, error register 0x%02X", node.cfg.node_id,
                   static_cast<unsigned>(code), static_cast<unsigned>(frame.data[2]));
  }
}

void CanopenEncoders::supervise_bus(TimeNs now) noexcept {
  const hal::CanBusState state = bus_.state();
  bus_stats_.bus_state = state;
  const bool off = state == hal::CanBusState::kBusOff || bus_off_by_frame_;
  if (off && !bus_off_) {
    bus_off_ = true;
    ++bus_stats_.bus_off_events;
    std::snprintf(last_error_, sizeof last_error_, "bus-off (%s): every node is invalid until the bus is back",
                  state == hal::CanBusState::kBusOff ? "the controller's state" : "an error frame");
    for (int i = 0; i < config_.node_count; ++i) {
      Node& node = nodes_[i];
      node.bus_off = true;
      node.resync = node.has_raw;
      node.reading.valid = false;
      node.reading.health = EncoderHealth::kBusOff;
    }
  } else if (!off && bus_off_) {
    bus_off_ = false;
    bus_back_seq_ = sync_seq_;
    // Nothing could be heard while off: heartbeat supervision starts afresh.
    for (int i = 0; i < config_.node_count; ++i) nodes_[i].last_hb = std::max(nodes_[i].last_hb, now);
  }
  bus_stats_.bus_off = bus_off_;
}

void CanopenEncoders::supervise_heartbeats(TimeNs now) noexcept {
  for (int i = 0; i < config_.node_count; ++i) {
    Node& node = nodes_[i];
    node.hb_timed_out = !bus_off_ && config_.heartbeat_timeout_ns > 0 && node.hb_seen &&
                        now - node.last_hb > config_.heartbeat_timeout_ns;
    if (node.hb_timed_out && !node.silent) {
      set_node_error(node, "node %d: no heartbeat for more than %lld ms", node.cfg.node_id,
                     static_cast<long long>(config_.heartbeat_timeout_ns / 1'000'000));
      node.silent = true;
      node.resync = node.has_raw;
      ++node.stats.silent_events;
      node.reading.valid = false;
      node.reading.health = EncoderHealth::kSilent;
    }
  }
}

void CanopenEncoders::detect_stuck(const SyncRecord& sync) noexcept {
  if (config_.stuck_time_ns <= 0) return;
  for (int i = 0; i < config_.node_count; ++i) {
    Node& node = nodes_[i];
    if (node.pending_samples == 0) continue;  // nothing new about this counter
    if (node.pending_step != 0) {
      node.still_ns = 0;
      node.others_moved.fill(0);
      node.stuck = false;
    } else {
      bool others_moving = false;
      std::int64_t most = 0;
      for (int j = 0; j < config_.node_count; ++j) {
        const Node& other = nodes_[j];
        if (j == i || other.pending_samples == 0 || other.silent) continue;
        std::int64_t& moved = node.others_moved[static_cast<std::size_t>(j)];
        moved += other.pending_step;
        others_moving = others_moving || other.pending_step != 0;
        most = std::max(most, abs64(moved));
      }
      // The clock runs only while someone else moves: a robot standing still
      // does not make every counter look stuck the moment it drives off.
      if (others_moving) node.still_ns += sync.time - node.prev_info_time;
      if (!node.stuck && node.still_ns >= config_.stuck_time_ns && most > config_.stuck_min_counts) {
        node.stuck = true;
        ++node.stats.stuck_events;
        set_node_error(node, "node %d: counter unchanged for %lld ms or more while another wheel moved %lld counts",
                       node.cfg.node_id, static_cast<long long>(config_.stuck_time_ns / 1'000'000),
                       static_cast<long long>(most));
      }
    }
    node.prev_info_time = sync.time;
  }
}

EncoderHealth CanopenEncoders::health_of(const Node& node, bool reported) const noexcept {
  if (bus_off_) return EncoderHealth::kBusOff;
  if (node.silent) return EncoderHealth::kSilent;
  if (node.bus_off) return EncoderHealth::kBusOff;
  if (!node.has_raw) return EncoderHealth::kNotStarted;
  if (!reported) return EncoderHealth::kNoSample;
  if (node.emcy_active) return EncoderHealth::kEmcy;
  if (node.stuck) return EncoderHealth::kStuck;
  if (node.reported_jump) return EncoderHealth::kJump;
  return EncoderHealth::kOk;
}

void CanopenEncoders::close_set(const SyncRecord& sync) noexcept {
  closed_seq_ = sync.seq;
  for (int i = 0; i < config_.node_count; ++i) {
    Node& node = nodes_[i];
    const bool reported = node.reported_seq == sync.seq;
    if (reported) {
      node.missed = 0;
    } else if (!bus_off_) {
      ++node.missed;
      ++node.stats.missed_syncs;
    }
    if (!node.silent && node.missed >= config_.tpdo_timeout_syncs) {
      set_node_error(node, "node %d: no TPDO for %d SYNCs in a row", node.cfg.node_id, node.missed);
      node.silent = true;
      node.resync = node.has_raw;
      ++node.stats.silent_events;
    } else if (node.silent && reported && !node.hb_timed_out) {
      node.silent = false;
    }
  }
  detect_stuck(sync);

  bool complete = true;
  int valid = 0;
  for (int i = 0; i < config_.node_count; ++i) {
    Node& node = nodes_[i];
    const bool reported = node.reported_seq == sync.seq;
    const EncoderHealth before = node.reading.health;
    const EncoderHealth health = health_of(node, reported);
    if (health == EncoderHealth::kOk && excluded(before)) ++node.stats.recoveries;
    EncoderReading& r = node.reading;
    r.health = health;
    r.valid = health == EncoderHealth::kOk;
    r.counts = node.counts;
    r.segment = node.segment;
    if (reported) {
      r.stamp = sync.time;
      r.sample_seq = sync.seq;
    }
    valid += r.valid ? 1 : 0;
    complete = complete && health != EncoderHealth::kNoSample;
    last_set_.readings[i] = r;
    node.pending_step = 0;
    node.pending_samples = 0;
    node.reported_jump = false;
  }
  last_set_.seq = sync.seq;
  last_set_.stamp = sync.time;
  last_set_.valid_count = valid;
  last_set_complete_ = complete;
  ++(complete ? bus_stats_.complete_sets : bus_stats_.incomplete_sets);
}

bool CanopenEncoders::take_sample_set(EncoderSampleSet* out) noexcept {
  if (out == nullptr || !last_set_complete_ || last_set_.seq <= taken_seq_) return false;
  *out = last_set_;
  taken_seq_ = last_set_.seq;
  return true;
}

}  // namespace rtfuse::drivers
