#include "sim/devices/canopen_encoder_node.hpp"

#include <cmath>

namespace rtfuse::sim {

namespace {
constexpr TimeNs kNsPerSecond = 1'000'000'000;
// After a long silence or a big time step a real node does not replay the
// heartbeats it missed; bounded catch-up also bounds work per advance().
constexpr int kMaxHeartbeatCatchUp = 4;
}  // namespace

CanopenEncoderNode::CanopenEncoderNode(const CanopenEncoderConfig& config) noexcept : config_(config) {
  if (config_.node_id < 1 || config_.node_id > 127) {
    config_.node_id = config_.node_id < 1 ? 1 : 127;
    valid_ = false;
  }
  if (config_.position_width < 1 || config_.position_width > 4) {
    config_.position_width = config_.position_width < 1 ? 1 : 4;
    valid_ = false;
  }
  if (config_.position_offset + config_.position_width > 8) {
    config_.position_offset = static_cast<std::uint8_t>(8 - config_.position_width);
    valid_ = false;
  }
  const int min_dlc = config_.position_offset + config_.position_width;
  if (config_.tpdo_dlc == 0) {
    config_.tpdo_dlc = static_cast<std::uint8_t>(min_dlc);
  } else if (config_.tpdo_dlc < min_dlc || config_.tpdo_dlc > 8) {
    config_.tpdo_dlc = static_cast<std::uint8_t>(min_dlc);
    valid_ = false;
  }
  if (config_.tpdo_cob_id == 0) config_.tpdo_cob_id = canopen::kTpdo1Base + config_.node_id;
  if (config_.heartbeat_period_ns < 0) {
    config_.heartbeat_period_ns = 0;
    valid_ = false;
  }
  base_counts_ = static_cast<double>(config_.initial_position);
}

void CanopenEncoderNode::rebase(TimeNs now) noexcept {
  if (base_time_set_) {
    const double speed = stuck_ ? 0.0 : config_.speed_counts_per_s;
    base_counts_ += speed * static_cast<double>(now - base_time_) / static_cast<double>(kNsPerSecond);
  }
  base_time_ = now;
  base_time_set_ = true;
}

void CanopenEncoderNode::set_speed(double counts_per_s, TimeNs now) noexcept {
  rebase(now);
  config_.speed_counts_per_s = counts_per_s;
}

void CanopenEncoderNode::set_position(std::int64_t counts, TimeNs now) noexcept {
  rebase(now);
  base_counts_ = static_cast<double>(counts);
  offset_ = 0;
}

std::int64_t CanopenEncoderNode::counts_at(TimeNs now) const noexcept {
  double counts = base_counts_;
  if (base_time_set_ && !stuck_) {
    counts += config_.speed_counts_per_s * static_cast<double>(now - base_time_) / static_cast<double>(kNsPerSecond);
  }
  return static_cast<std::int64_t>(std::floor(counts)) + offset_;
}

std::int64_t CanopenEncoderNode::position_value(TimeNs now) const noexcept {
  const int bits = 8 * config_.position_width;
  const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
  const std::uint64_t raw = static_cast<std::uint64_t>(counts_at(now)) & mask;
  if (config_.position_signed && (raw >> (bits - 1)) != 0) {
    return static_cast<std::int64_t>(raw) - static_cast<std::int64_t>(std::uint64_t{1} << bits);
  }
  return static_cast<std::int64_t>(raw);
}

void CanopenEncoderNode::set_silent(bool silent, TimeNs now) noexcept {
  if (silent_ && !silent && booted_ && config_.heartbeat_period_ns > 0) {
    // Keep the heartbeat phase; skip the beats that fell in the silence.
    const TimeNs period = config_.heartbeat_period_ns;
    if (next_heartbeat_ <= now) next_heartbeat_ += ((now - next_heartbeat_) / period + 1) * period;
  }
  silent_ = silent;
}

void CanopenEncoderNode::set_stuck(bool stuck, TimeNs now) noexcept {
  rebase(now);
  stuck_ = stuck;
}

void CanopenEncoderNode::boot(TimeNs now, hal::mock::CanWire& wire) noexcept {
  booted_ = true;
  ++boot_count_;
  state_ = canopen::NmtState::kPreOperational;
  next_heartbeat_ = now + config_.heartbeat_period_ns;
  hal::CanFrame f;
  f.id = canopen::kHeartbeatBase + config_.node_id;
  f.dlc = 1;
  f.data[0] = static_cast<std::uint8_t>(canopen::NmtState::kBootUp);
  wire.transmit(f, now);
}

bool CanopenEncoderNode::emit_emcy(std::uint16_t error_code, std::uint8_t error_register,
                                   const std::uint8_t manufacturer[5], TimeNs now, hal::mock::CanWire& wire) noexcept {
  if (silent_ || !booted_ || state_ == canopen::NmtState::kStopped) return false;
  hal::CanFrame f;
  f.id = canopen::kEmcyBase + config_.node_id;
  f.dlc = 8;
  f.data[0] = static_cast<std::uint8_t>(error_code & 0xFF);
  f.data[1] = static_cast<std::uint8_t>(error_code >> 8);
  f.data[2] = error_register;
  for (int i = 0; i < 5; ++i) f.data[3 + i] = manufacturer != nullptr ? manufacturer[i] : 0;
  return wire.transmit(f, now);
}

void CanopenEncoderNode::send_tpdo(TimeNs now, hal::mock::CanWire& wire) noexcept {
  hal::CanFrame f;
  f.id = config_.tpdo_cob_id;
  f.dlc = config_.tpdo_dlc;
  const std::uint64_t raw = static_cast<std::uint64_t>(counts_at(now));
  for (int i = 0; i < config_.position_width; ++i) {
    f.data[config_.position_offset + i] = static_cast<std::uint8_t>(raw >> (8 * i));
  }
  if (wire.transmit(f, now)) ++tpdo_count_;
}

void CanopenEncoderNode::handle_nmt(const hal::CanFrame& frame, TimeNs now, hal::mock::CanWire& wire) noexcept {
  // CiA 301 NMT node control is exactly two bytes; stacks drop anything else.
  if (frame.dlc != 2) return;
  const std::uint8_t target = frame.data[1];
  if (target != 0 && target != config_.node_id) return;
  switch (frame.data[0]) {
    case canopen::kNmtStart: state_ = canopen::NmtState::kOperational; break;
    case canopen::kNmtStop: state_ = canopen::NmtState::kStopped; break;
    case canopen::kNmtEnterPreOperational: state_ = canopen::NmtState::kPreOperational; break;
    case canopen::kNmtResetNode:
    case canopen::kNmtResetCommunication:
      // Both end in a fresh boot-up. The encoder's position is physics, not an
      // application parameter, so it survives a reset node.
      boot(now, wire);
      break;
    default: break;
  }
}

void CanopenEncoderNode::on_frame(const hal::CanFrame& frame, TimeNs now, hal::mock::CanWire& wire) noexcept {
  if (silent_ || !booted_ || frame.extended || frame.rtr || frame.error) return;
  advance(now, wire);  // a heartbeat due before this frame goes out first
  if (frame.id == canopen::kNmtCobId) {
    handle_nmt(frame, now, wire);
  } else if (frame.id == canopen::kSyncCobId) {
    if (state_ == canopen::NmtState::kOperational) send_tpdo(now, wire);
  }
}

void CanopenEncoderNode::advance(TimeNs now, hal::mock::CanWire& wire) noexcept {
  if (!base_time_set_) {
    base_time_ = now;
    base_time_set_ = true;
  }
  if (silent_) return;
  if (!booted_) {
    boot(now, wire);
    return;
  }
  const TimeNs period = config_.heartbeat_period_ns;
  if (period <= 0) return;
  int emitted = 0;
  while (next_heartbeat_ <= now) {
    if (emitted == kMaxHeartbeatCatchUp) {
      next_heartbeat_ += ((now - next_heartbeat_) / period + 1) * period;
      break;
    }
    hal::CanFrame f;
    f.id = canopen::kHeartbeatBase + config_.node_id;
    f.dlc = 1;
    f.data[0] = static_cast<std::uint8_t>(state_);
    wire.transmit(f, next_heartbeat_);
    next_heartbeat_ += period;
    ++emitted;
  }
}

}  // namespace rtfuse::sim
