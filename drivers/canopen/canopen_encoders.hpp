#pragma once
// CiA 301 / CiA 406 master for up to kMaxEncoderNodes rotary encoders on one
// CAN bus, polled by the loop: no threads, no blocking, no allocation after
// create().
//
// Timing model. Every poll() ends by sending one SYNC. The encoders' TPDOs are
// synchronous (transmission type 1..240): a device latches its position when
// it receives SYNC k and transmits it afterwards. So a TPDO received after
// SYNC k went out (and before SYNC k+1) is the position at SYNC k, and its
// sample time is the time SYNC k was sent, not its receive time. The driver
// keeps the send times of the last SYNCs and attributes each TPDO by its
// receive stamp, so frames left queued by the per-poll frame bound are still
// attributed right.
//
// poll(now):
//   1. drain the RX queue without blocking, at most max_frames_per_poll frames;
//   2. process every frame (TPDO, heartbeat, EMCY, error frames; the rest is
//      counted and dropped);
//   3. supervision: bus-off, heartbeat and TPDO timeouts, stuck counters,
//      pending NMT starts; close the sample set of the last SYNC;
//   4. send the next SYNC.
// So the set of SYNC k is complete in the poll after the one that sent it.
//
// Wrap-around: counters of 8..32 bits are unwrapped to int64 taking the
// shortest way between two samples; that is exact only while an encoder moves
// less than half its counter range between two received samples (an 8-bit
// counter at a 200 Hz SYNC: < 128 counts per 5 ms = 25'600 counts/s).
//
// Faults (each counted in EncoderNodeStats, the node excluded with the reason
// in EncoderReading::health, and recovered without a restart):
//   silent   heartbeat timeout (after the first heartbeat) or tpdo_timeout_syncs
//            SYNCs without a TPDO; back on the first TPDO with a fresh heartbeat.
//            A boot-up, pre-operational or stopped heartbeat gets an NMT start
//            (at most one per nmt_restart_interval_ns per node).
//   stuck    counter unchanged for stuck_time_ns while another node moved more
//            than stuck_min_counts; back as soon as it counts again. A pivot
//            turn about one wheel longer than stuck_time_ns looks the same.
//   jump     |step| > max_counts_per_s * dt + 1: that sample is rejected and the
//            unwrap re-based on it (a new segment), so a permanent offset
//            costs one sample and a one-sample spike two.
//   bus-off  hal::CanBusState::kBusOff or a bus-off error frame: every node is
//            invalid until the bus is back and that node's next TPDO arrives.
//   EMCY     error code != 0x0000 excludes the node until an error-reset EMCY
//            (code 0x0000) or a boot-up; count and last code/register kept.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "core/time.hpp"
#include "drivers/canopen/canopen_encoders_config.hpp"
#include "drivers/canopen/encoder_reading.hpp"
#include "hal/can_bus.hpp"

namespace rtfuse::drivers {

class CanopenEncoders {
 public:
  // nullptr with *error set when the config is invalid (see validate_config).
  static std::unique_ptr<CanopenEncoders> create(hal::CanBus& bus, const CanopenEncodersConfig& config,
                                                 std::string* error);
  ~CanopenEncoders();
  CanopenEncoders(const CanopenEncoders&) = delete;
  CanopenEncoders& operator=(const CanopenEncoders&) = delete;

  // NMT "start remote node" to every configured node. False when the bus
  // refused a send (last_error() says which and why); the others are still sent.
  bool start(TimeNs now) noexcept;
  // Once per loop tick (see the header comment). Never blocks, never allocates.
  void poll(TimeNs now) noexcept;

  // True once for each new complete sample set: every node that is not
  // excluded answered the same SYNC. Excluded nodes appear invalid in it.
  bool take_sample_set(EncoderSampleSet* out) noexcept;
  // The set closed last, complete or not.
  const EncoderSampleSet& last_set() const noexcept { return last_set_; }

  int node_count() const noexcept { return config_.node_count; }
  const EncoderReading& reading(int node) const noexcept;
  const EncoderNodeStats& node_stats(int node) const noexcept;
  const CanopenBusStats& bus_stats() const noexcept { return bus_stats_; }
  const CanopenEncodersConfig& config() const noexcept { return config_; }
  // Text of the bus's last failure: a refused send, a failed receive, a
  // malformed frame, bus-off ("" if none). Kept after the bus recovers.
  const char* last_error() const noexcept { return last_error_; }
  // Text of the node's last fault: silent, EMCY, stuck, jump ("" if none).
  // Kept after the node recovers. Bus-off is the bus's, in last_error().
  const char* node_error(int node) const noexcept;

 private:
  struct Node;
  struct SyncRecord {
    std::int64_t seq = 0;
    TimeNs time = 0;
  };
  enum class Object : std::uint8_t { kNone, kTpdo, kHeartbeat, kEmcy };

  CanopenEncoders(hal::CanBus& bus, const CanopenEncodersConfig& config);

  void process(const hal::CanFrame& frame) noexcept;
  void on_tpdo(Node& node, const hal::CanFrame& frame) noexcept;
  void on_heartbeat(Node& node, const hal::CanFrame& frame) noexcept;
  void on_emcy(Node& node, const hal::CanFrame& frame) noexcept;
  void on_error_frame(const hal::CanFrame& frame) noexcept;
  bool find_sync(TimeNs stamp, SyncRecord* out) const noexcept;

  void supervise_bus(TimeNs now) noexcept;
  void supervise_heartbeats(TimeNs now) noexcept;
  void close_set(const SyncRecord& sync) noexcept;
  void detect_stuck(const SyncRecord& sync) noexcept;
  EncoderHealth health_of(const Node& node, bool reported) const noexcept;
  bool send_nmt_start(Node& node, TimeNs now) noexcept;
  void send_sync(TimeNs now) noexcept;
  void set_error(const char* what, std::uint32_t cob_id) noexcept;
  void malformed(const hal::CanFrame& frame) noexcept;
  static void set_node_error(Node& node, const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  hal::CanBus& bus_;
  CanopenEncodersConfig config_;
  std::unique_ptr<Node[]> nodes_;

  // COB-ID -> (node index, object) for O(1) dispatch of 11-bit ids.
  std::array<std::uint8_t, cia301::kMaxStandardId + 1> owner_{};
  std::array<Object, cia301::kMaxStandardId + 1> object_{};

  static constexpr int kSyncHistory = 16;
  std::array<SyncRecord, kSyncHistory> syncs_{};
  std::int64_t sync_seq_ = 0;         // last SYNC sent
  std::int64_t closed_seq_ = 0;       // last SYNC whose set was closed
  std::int64_t taken_seq_ = 0;        // last set handed out by take_sample_set
  bool last_set_complete_ = false;
  EncoderSampleSet last_set_;

  // Bus-off is latched from two sources: the bus state, and an error frame
  // (cleared by a "restarted" error frame or a data frame received after it).
  bool bus_off_ = false;
  bool bus_off_by_frame_ = false;
  TimeNs bus_off_frame_stamp_ = 0;
  std::int64_t bus_back_seq_ = 0;  // TPDOs of SYNCs after this one clear a node's bus-off

  static constexpr int kRxBatch = 16;
  std::array<hal::CanFrame, kRxBatch> rx_{};

  CanopenBusStats bus_stats_;
  char last_error_[160] = {};
};

}  // namespace rtfuse::drivers
