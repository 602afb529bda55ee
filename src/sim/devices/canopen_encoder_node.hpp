#pragma once
// A CiA 301 / CiA 406 rotary encoder as a device on a hal::mock::MockCanBus (or, through
// rtfuse-canopen-node, on a real CAN interface), behaving
// the way a real one does on the wire, so the encoder driver can be tested
// (and a simulated robot driven) without hardware:
//
//  - NMT slave: Initialisation -> boot-up frame (0x700+id, one byte 0x00) ->
//    Pre-operational; start (0x01) -> Operational, stop (0x02) -> Stopped,
//    enter pre-operational (0x80), reset node (0x81) and reset communication
//    (0x82) -> a new boot-up and Pre-operational. Commands arrive on COB-ID
//    0x000 with data [command, node-id]; node-id 0 addresses every node.
//  - Heartbeat producer on 0x700+id: one byte, the NMT state (0x04 stopped,
//    0x05 operational, 0x7F pre-operational), every heartbeat period, in
//    every state (error control stays active in Stopped).
//  - Synchronous TPDO1 (0x180+id by default): on each SYNC (COB-ID 0x080)
//    while Operational, the position value little-endian at a configurable
//    byte offset and width. PDOs are silent in Pre-operational and Stopped.
//  - EMCY (0x080+id, 8 bytes: error code LE, error register, 5 manufacturer
//    bytes) on request, except in Stopped where only NMT and heartbeat run.
//
// The position is the integral of a settable speed, floored to whole counts
// and wrapped at the configured width (two's complement, so signed and
// unsigned encoders put the same bytes on the wire; signedness only changes
// how position_value() reads them).
#include <cstdint>

#include "hal/mock/mock_can_bus.hpp"

namespace rtfuse::sim {

// CiA 301 constants a driver and the device model must agree on.
namespace canopen {
constexpr std::uint32_t kNmtCobId = 0x000;
constexpr std::uint32_t kSyncCobId = 0x080;
constexpr std::uint32_t kEmcyBase = 0x080;
constexpr std::uint32_t kTpdo1Base = 0x180;
constexpr std::uint32_t kHeartbeatBase = 0x700;

constexpr std::uint8_t kNmtStart = 0x01;
constexpr std::uint8_t kNmtStop = 0x02;
constexpr std::uint8_t kNmtEnterPreOperational = 0x80;
constexpr std::uint8_t kNmtResetNode = 0x81;
constexpr std::uint8_t kNmtResetCommunication = 0x82;

// The byte a heartbeat carries; kBootUp is the boot-up frame's only byte.
enum class NmtState : std::uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
};
}  // namespace canopen

struct CanopenEncoderConfig {
  std::uint8_t node_id = 1;                    // 1..127
  TimeNs heartbeat_period_ns = 100'000'000;    // 0: no heartbeat (object 0x1017 = 0)
  std::uint32_t tpdo_cob_id = 0;               // 0: 0x180 + node_id
  std::uint8_t position_offset = 0;            // first byte of the value in the TPDO
  std::uint8_t position_width = 4;             // bytes, 1..4
  bool position_signed = false;
  std::uint8_t tpdo_dlc = 0;                   // 0: offset + width
  double speed_counts_per_s = 0.0;
  std::int64_t initial_position = 0;           // counts at power-up
};

class CanopenEncoderNode final : public hal::mock::CanNode {
 public:
  // An invalid layout (width outside 1..4, value past byte 8) is clamped to
  // the nearest valid one; valid() says whether the config was taken as is.
  explicit CanopenEncoderNode(const CanopenEncoderConfig& config) noexcept;

  // --- physics (the wheel) --------------------------------------------------
  // The shaft turns at `counts_per_s` from `now` on.
  void set_speed(double counts_per_s, TimeNs now) noexcept;
  // Puts the shaft at `counts` at `now` (e.g. a preset).
  void set_position(std::int64_t counts, TimeNs now) noexcept;
  // Unwrapped counts the encoder has registered at `now` (faults included).
  std::int64_t counts_at(TimeNs now) const noexcept;
  // What a TPDO sent at `now` carries, read with the configured width and
  // signedness.
  std::int64_t position_value(TimeNs now) const noexcept;

  // --- faults ---------------------------------------------------------------
  // A silent node is off the bus (cable cut, power lost): it sends nothing and
  // hears nothing, not even NMT. The shaft keeps turning. When it comes back
  // its heartbeat resumes on the next period, without a burst of missed ones.
  void set_silent(bool silent, TimeNs now) noexcept;
  // A stuck counter stops counting (the reported value freezes) while the
  // node otherwise works; released, it counts on from where it stopped.
  void set_stuck(bool stuck, TimeNs now) noexcept;
  // The counter jumps by `counts` at once (a glitch, a bad preset).
  void jump(std::int64_t counts) noexcept { offset_ += counts; }
  // Sends an EMCY now. False when silent, stopped or not yet booted.
  bool emit_emcy(std::uint16_t error_code, std::uint8_t error_register, const std::uint8_t manufacturer[5],
                 TimeNs now, hal::mock::CanWire& wire) noexcept;

  // --- inspection -------------------------------------------------------------
  canopen::NmtState nmt_state() const noexcept { return state_; }
  bool booted() const noexcept { return booted_; }
  int boot_count() const noexcept { return boot_count_; }
  std::int64_t tpdo_count() const noexcept { return tpdo_count_; }
  std::uint8_t node_id() const noexcept { return config_.node_id; }
  std::uint32_t tpdo_cob_id() const noexcept { return config_.tpdo_cob_id; }
  const CanopenEncoderConfig& config() const noexcept { return config_; }
  bool valid() const noexcept { return valid_; }

  // --- hal::mock::CanNode ----------------------------------------------------------------
  void on_frame(const hal::CanFrame& frame, TimeNs now, hal::mock::CanWire& wire) noexcept override;
  void advance(TimeNs now, hal::mock::CanWire& wire) noexcept override;

 private:
  void boot(TimeNs now, hal::mock::CanWire& wire) noexcept;
  void rebase(TimeNs now) noexcept;
  void handle_nmt(const hal::CanFrame& frame, TimeNs now, hal::mock::CanWire& wire) noexcept;
  void send_tpdo(TimeNs now, hal::mock::CanWire& wire) noexcept;

  CanopenEncoderConfig config_;
  bool valid_ = true;

  canopen::NmtState state_ = canopen::NmtState::kBootUp;
  bool booted_ = false;
  int boot_count_ = 0;
  TimeNs next_heartbeat_ = 0;
  std::int64_t tpdo_count_ = 0;

  // position(t) = floor(base_counts_ + speed * (t - base_time_)) + offset_;
  // rebased whenever speed or stuck changes so a change never moves the past.
  double base_counts_ = 0.0;
  TimeNs base_time_ = 0;
  bool base_time_set_ = false;
  std::int64_t offset_ = 0;

  bool silent_ = false;
  bool stuck_ = false;
};

}  // namespace rtfuse::sim
