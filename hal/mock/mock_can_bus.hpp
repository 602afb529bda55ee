#pragma once
// A virtual CAN bus for tests, replay and simulation. Time is whatever the
// owner says (set_time, or a hal::Clock such as the simulated one), so runs
// are deterministic; nothing here ever blocks or sleeps.
//
// Frames a test injects, and frames the attached device models (CanNode)
// answer with, come out of receive() in the order they were injected. Frames
// the driver sends are kept in a log and shown to every node, as the wire
// would carry them to every device.
//
// Allocation happens in the constructor only: the receive queue, the send log
// and the node table have fixed capacities.
#include <cstdint>
#include <memory>

#include "hal/can_bus.hpp"
#include "hal/clock.hpp"

namespace rtfuse::hal::mock {

// Where a device model's frames go: the mock bus's receive queue, or a real
// CAN interface when the same model runs as a stand-alone node on a wire
// (rtfuse-canopen-node). False when the frame could not be sent.
class CanWire {
 public:
  virtual ~CanWire() = default;
  // `stamp` is when the device sent it: a heartbeat that fell due between two
  // looks at the clock carries its due time. A real wire stamps on its own.
  virtual bool transmit(const CanFrame& frame, TimeNs stamp) noexcept = 0;
};

// A device on the virtual bus (see sim/devices/canopen_encoder_node.hpp).
// Nodes answer through the wire; they do not see each other's frames, only
// the ones the host sends, which is all a device model under test needs.
class CanNode {
 public:
  virtual ~CanNode() = default;
  // A frame the host sent; `now` is the bus time of transmission.
  virtual void on_frame(const CanFrame& frame, TimeNs now, CanWire& wire) noexcept = 0;
  // Bus time moved to `now`: emit whatever became due (heartbeats...). Must be
  // idempotent for repeated calls with the same `now`: the bus calls it
  // whenever it looks at the time.
  virtual void advance(TimeNs now, CanWire& wire) noexcept = 0;
};

struct MockCanBusCapacity {
  int rx_frames = 256;   // frames waiting for receive(); more are dropped and counted
  int sent_frames = 1024;  // the send log keeps the most recent this many
  int nodes = 16;
};

class MockCanBus final : public CanBus, public CanWire {
 public:
  // With a clock, bus time is clock->now(); without one it is set_time()'s.
  explicit MockCanBus(MockCanBusCapacity capacity = {}, const Clock* clock = nullptr);
  ~MockCanBus() override;
  MockCanBus(const MockCanBus&) = delete;
  MockCanBus& operator=(const MockCanBus&) = delete;

  // --- time ---------------------------------------------------------------
  TimeNs now() const noexcept;
  // Moves manual time (ignored while a clock is set) and lets the nodes emit
  // what became due up to it.
  void set_time(TimeNs t) noexcept;
  void set_clock(const Clock* clock) noexcept { clock_ = clock; }
  // Lets every node emit what is due at now(). receive() and send() do this
  // themselves; call it when time moved through a Clock and nobody polled.
  void advance_nodes() noexcept { advance_nodes_to(now()); }

  // --- devices ------------------------------------------------------------
  // The node is called at once with advance(now): a device powers up when it
  // is plugged in (a CANopen node sends its boot-up). False when the node
  // table is full or the node is already attached. The bus does not own it.
  bool attach(CanNode& node) noexcept;
  void detach(CanNode& node) noexcept;
  int node_count() const noexcept { return node_count_; }

  // --- what the host receives ---------------------------------------------
  // Queues a frame stamped with now(). False (and counted in rx_dropped) when
  // the queue is full, as a kernel socket buffer drops on overrun.
  bool inject(const CanFrame& frame) noexcept { return inject_at(frame, now()); }
  // Same, with an explicit stamp: a node emitting a heartbeat that fell due
  // between two looks at the clock stamps it with its due time.
  bool inject_at(const CanFrame& frame, TimeNs stamp) noexcept;
  // CanWire: what the attached nodes send is queued like inject_at().
  bool transmit(const CanFrame& frame, TimeNs stamp) noexcept override { return inject_at(frame, stamp); }
  int pending() const noexcept { return rx_count_; }
  std::int64_t rx_dropped() const noexcept { return rx_dropped_; }

  // --- what the host sent -------------------------------------------------
  // sent(0) is the oldest frame still in the log; stamps are the send time.
  const CanFrame& sent(int i) const noexcept;
  int sent_count() const noexcept { return sent_count_; }
  std::int64_t total_sent() const noexcept { return total_sent_; }
  void clear_sent() noexcept;

  // --- faults -------------------------------------------------------------
  // The state a backend would have learnt from error frames. In bus-off the
  // controller transmits nothing: send() fails with kBusError and no node sees
  // the frame. Queued frames can still be received.
  void set_state(CanBusState state) noexcept { state_ = state; }
  // The next `count` sends fail with `status`; the frame never reaches the bus.
  void fail_next_send(HalStatus status, int count = 1) noexcept;

  // --- hal::CanBus --------------------------------------------------------
  HalStatus send(const CanFrame& frame) noexcept override;
  // Never waits. Nodes first emit what is due at now(). With timeout_ns > 0
  // and nothing queued it behaves as if the caller had waited:
  //  - manual time: nodes advance to now()+timeout; if any answered, time
  //    moves to the latest answer's stamp (everything due by then arrives in
  //    one batch, which drivers handle anyway), otherwise to now()+timeout
  //    and the result is kTimeout;
  //  - with a clock: the clock's owner moves time, so the result is kTimeout
  //    at once (the caller's next poll sees what became due meanwhile).
  // timeout_ns 0 with nothing queued: kWouldBlock.
  int receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept override;
  CanBusState state() const noexcept override { return state_; }
  const char* last_error() const noexcept override { return last_error_; }

 private:
  void advance_nodes_to(TimeNs t) noexcept;
  int drain(CanFrame* out, int max) noexcept;

  const Clock* clock_;
  TimeNs manual_now_ = 0;
  CanBusState state_ = CanBusState::kErrorActive;
  const char* last_error_ = "";

  std::unique_ptr<CanFrame[]> rx_;
  int rx_capacity_;
  int rx_head_ = 0;
  int rx_count_ = 0;
  std::int64_t rx_dropped_ = 0;

  std::unique_ptr<CanFrame[]> sent_;
  int sent_capacity_;
  int sent_head_ = 0;
  int sent_count_ = 0;
  std::int64_t total_sent_ = 0;

  std::unique_ptr<CanNode*[]> nodes_;
  int node_capacity_;
  int node_count_ = 0;

  HalStatus fail_status_ = HalStatus::kOk;
  int fail_count_ = 0;
};

}  // namespace rtfuse::hal::mock
