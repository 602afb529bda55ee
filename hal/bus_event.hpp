#pragma once
// One bus call a driver made and what it got back, as a fixed-size, trivially
// copyable record: the recording decorators push these into an SPSC ring per
// producing thread (no allocation, no blocking), the recorder thread writes
// them to an LCM log, and replay hands the recorded results back.
//
// A BusEvent is canonical when every field the kind does not use is zero:
// the decorators and the decoder only ever produce canonical events, so two
// recordings of the same call compare equal byte for byte.
#include <atomic>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/spsc_ring.hpp"
#include "core/time.hpp"
#include "hal/can_bus.hpp"
#include "hal/status.hpp"

namespace rtfuse::hal {

enum class BusEventKind : std::uint8_t {
  kNone,
  kCanSend,
  kCanReceive,
  kI2cRead,
  kI2cWrite,
  kGpioWaitEdge,
  kGpioSet,
  kClockNow,
  kClockSleepUntil,
  kSerialRead,
  kSerialWrite,
  kSerialReopen,
};

// The call's name as divergence reports and logs spell it.
inline const char* to_string(BusEventKind k) noexcept {
  switch (k) {
    case BusEventKind::kNone: return "none";
    case BusEventKind::kCanSend: return "can_send";
    case BusEventKind::kCanReceive: return "can_receive";
    case BusEventKind::kI2cRead: return "i2c_read";
    case BusEventKind::kI2cWrite: return "i2c_write";
    case BusEventKind::kGpioWaitEdge: return "gpio_wait_edge";
    case BusEventKind::kGpioSet: return "gpio_set";
    case BusEventKind::kClockNow: return "clock_now";
    case BusEventKind::kClockSleepUntil: return "clock_sleep_until";
    case BusEventKind::kSerialRead: return "serial_read";
    case BusEventKind::kSerialWrite: return "serial_write";
    case BusEventKind::kSerialReopen: return "serial_reopen";
  }
  return "unknown";
}

// Frames one can_receive event holds. The recording decorator caps receive()'s
// `max` at this, in recording and in replay alike, so one call is always one
// event (the CanBus contract already lets receive return fewer than asked).
constexpr int kBusEventMaxFrames = 16;
// The I2cBus contract's largest read, and the most bytes one serial_read or
// serial_write event holds: the recording decorator caps a serial read's
// `max` at this and splits a longer write, in recording and replay alike.
constexpr int kBusEventMaxBytes = 64;

struct BusEvent {
  TimeNs time_ns = 0;     // clock time of the call; 0 when the decorator has no clock
  TimeNs timeout_ns = 0;  // can_receive / gpio_wait_edge / serial_read: the timeout argument
  TimeNs clock_ns = 0;    // clock_now: the value returned; clock_sleep_until: the deadline
  // gpio_wait_edge with kOk: the edge's kernel stamp; serial_read with
  // bytes: when the port saw them.
  TimeNs edge_stamp = 0;
  std::int64_t retries = 0;  // i2c: the bus's retries() counter after the call
  // i2c_read: bytes asked for; i2c_write: 1; can_receive and serial_read:
  // `max` after the cap; serial_write: bytes written.
  std::int32_t length = 0;
  // Events of the same decorator that found the ring full just before this
  // one: the recording has a hole here.
  std::uint32_t lost_before = 0;

  BusEventKind kind = BusEventKind::kNone;
  std::uint8_t device = 0;  // index of the recorded bus instance (the recording's device table)
  HalStatus status = HalStatus::kOk;
  CanBusState bus_state = CanBusState::kUnknown;  // can: state() after the call
  std::uint8_t count = 0;    // can_send: 1; can_receive: frames returned; serial_read: bytes returned
  std::uint8_t address = 0;  // i2c: 7-bit device address
  std::uint8_t reg = 0;      // i2c: register
  std::uint8_t value = 0;    // i2c_write: the byte written
  std::uint8_t level = 0;    // gpio_wait_edge: 1 rising edge; gpio_set: the level set
  std::uint8_t reserved[7] = {};  // explicit so the layout has no padding bytes

  CanFrame frames[kBusEventMaxFrames] = {};  // can_send: frames[0]; can_receive: count frames
  // i2c_read with kOk: `length` bytes read; serial_read: `count` bytes
  // read; serial_write: the `length` bytes written.
  std::uint8_t data[kBusEventMaxBytes] = {};
};

static_assert(std::is_trivially_copyable_v<BusEvent>, "BusEvent travels through SPSC rings by copy");
static_assert(std::has_unique_object_representations_v<BusEvent>,
              "no padding: equal events are equal bytes (the codec round trip relies on it)");
static_assert(sizeof(BusEvent) == 512, "layout changed: check the codec and the replay compaction");

// Equality of every byte: the layout has no padding, so that is every field.
inline bool operator==(const BusEvent& a, const BusEvent& b) noexcept {
  return std::memcmp(&a, &b, sizeof(BusEvent)) == 0;
}
inline bool operator!=(const BusEvent& a, const BusEvent& b) noexcept { return !(a == b); }

// The producer end a recording decorator writes through: stamps the device
// index, never blocks, and when the ring is full drops the event, counts it,
// and tells the next event that got through how many went missing before it
// (so the log itself says where it is incomplete). Used by one thread only,
// the one the ring belongs to.
class BusEventTap {
 public:
  BusEventTap(SpscRing<BusEvent>& ring, std::uint8_t device) noexcept : ring_(ring), device_(device) {}

  bool push(BusEvent& ev) noexcept {
    ev.device = device_;
    ev.lost_before = pending_lost_;
    if (ring_.try_push(ev)) {
      pending_lost_ = 0;
      return true;
    }
    if (pending_lost_ < std::numeric_limits<std::uint32_t>::max()) ++pending_lost_;
    overflows_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  std::uint8_t device() const noexcept { return device_; }
  // Events lost to a full ring since construction; readable from any thread.
  std::int64_t overflows() const noexcept { return overflows_.load(std::memory_order_relaxed); }

 private:
  SpscRing<BusEvent>& ring_;
  std::uint8_t device_;
  std::uint32_t pending_lost_ = 0;
  std::atomic<std::int64_t> overflows_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free, "RT path needs lock-free atomics");
};

}  // namespace rtfuse::hal
