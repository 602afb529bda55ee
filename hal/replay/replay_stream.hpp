#pragma once
// The recorded bus calls of one producing thread (the loop, the IMU thread),
// in call order, handed back one by one to the replay buses that thread's
// drivers use. Each replay call is checked against the next recorded one: the
// same kind of call on the same device with the same arguments gets the
// recorded result; anything else stops the replay with a divergence report
// naming the log event, the recorded call and the attempted call, e.g.
//
//   event 1234: recorded can_send id 0x080 dlc 0, driver sent id 0x000 dlc 2 [01 05]
//
// Loading (append, names) may allocate and happens before the replay starts.
// take() and everything the replay thread calls never allocate, lock or
// block. One thread replays a stream; diverged(), position() and the report
// may be read from any other thread (the report once diverged() is true).
//
// Events are stored compacted (a fixed head, then only the frames and bytes
// the call used) and expanded into one scratch event on take(): a recording
// at IMU rate holds millions of calls, and a full BusEvent is 512 bytes.
// Compaction keeps canonical events (unused fields zero) exactly.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hal/bus_event.hpp"

namespace rtfuse::hal::replay {

enum class DivergenceKind : std::uint8_t {
  kNone,
  kMismatch,     // a call that is not the recorded one
  kEndOfStream,  // a call after the last recorded one (or past a hole in the recording)
};

class ReplayStream {
 public:
  static constexpr std::size_t kReportSize = 512;

  explicit ReplayStream(std::string name = "replay");
  ReplayStream(const ReplayStream&) = delete;
  ReplayStream& operator=(const ReplayStream&) = delete;

  // --- loading (before the replay starts) ---------------------------------
  void reserve(std::size_t events);
  // One recorded call; log_event is its event number in the log file.
  void append(const BusEvent& ev, std::int64_t log_event);
  // The recorder lost `lost` events of this thread after the last appended
  // one (its ring was full): the replay can only go that far, and the report
  // at the end says why.
  void mark_hole(std::int64_t log_event, std::uint32_t lost);
  // Names reports use for device indices ("can0"); "device N" otherwise.
  void set_device_name(std::uint8_t device, std::string name);

  // --- replay (the stream's thread) ---------------------------------------
  // `call` carries the kind, device and arguments of the attempted call (the
  // result fields are ignored). Returns the recorded event, valid until the
  // next take(), when it is the same call; otherwise nullptr, and the
  // divergence is set (the first one wins) and every later take() fails.
  const BusEvent* take(const BusEvent& call) noexcept;

  bool diverged() const noexcept { return kind_.load(std::memory_order_acquire) != DivergenceKind::kNone; }
  DivergenceKind divergence_kind() const noexcept { return kind_.load(std::memory_order_acquire); }
  // The report ("" until diverged).
  const char* divergence() const noexcept { return diverged() ? report_ : ""; }
  // Log event number the report is about (the recorded call that did not
  // match, or the last one replayed at the end of the stream); -1 if none.
  std::int64_t divergence_event() const noexcept { return diverged() ? report_event_ : -1; }
  // Every recorded call was replayed and none differed: a clean stop, even if
  // a driver then tried one more call.
  bool at_end() const noexcept {
    return position() == size() && divergence_kind() != DivergenceKind::kMismatch;
  }
  std::size_t position() const noexcept { return position_.load(std::memory_order_acquire); }
  std::size_t size() const noexcept { return heads_.size(); }
  std::size_t remaining() const noexcept { return size() - position(); }

  // --- inspection (tools, tests) -------------------------------------------
  const std::string& name() const { return name_; }
  // The i-th recorded event, expanded, and its log event number.
  BusEvent event(std::size_t i) const noexcept;
  std::int64_t log_event(std::size_t i) const noexcept { return heads_[i].log_event; }
  bool has_hole() const noexcept { return hole_lost_ > 0; }
  std::int64_t hole_event() const noexcept { return hole_event_; }

 private:
  struct Head {
    std::int64_t log_event;
    std::size_t offset;  // into bytes_
  };

  void expand(std::size_t i, BusEvent* out) const noexcept;
  void diverge(DivergenceKind kind, std::int64_t log_event, const BusEvent* recorded,
               const BusEvent& call) noexcept;
  const char* device_name(std::uint8_t device, char* scratch, std::size_t size) const noexcept;
  int describe(char* buf, std::size_t size, const BusEvent& ev, bool attempted, bool with_device) const noexcept;

  std::string name_;
  std::vector<Head> heads_;
  std::vector<std::uint8_t> bytes_;
  std::vector<std::string> device_names_;
  std::int64_t hole_event_ = -1;
  std::uint32_t hole_lost_ = 0;

  BusEvent current_;
  std::atomic<std::size_t> position_{0};
  std::atomic<DivergenceKind> kind_{DivergenceKind::kNone};
  std::int64_t report_event_ = -1;
  char report_[kReportSize] = {};
};

}  // namespace rtfuse::hal::replay
