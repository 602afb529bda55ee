#pragma once
// The recorded bus calls of one producing thread (the loop, the IMU thread),
// in call order, handed back one by one to the replay buses that thread's
// drivers use. Each replay call is checked against the next recorded one by
// the rules every replay follows (hal/replay/replay_cursor.hpp): the same
// kind of call on the same device with the same arguments gets the recorded
// result; anything else stops the replay with a divergence report naming the
// log event, the recorded call and the attempted call, e.g.
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
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hal/bus_event.hpp"
#include "hal/replay/replay_cursor.hpp"
#include "hal/replay/report_text.hpp"

namespace rtfuse::hal::replay {

class ReplayStream : public ReplayCursor<ReplayStream, BusEvent> {
 public:
  explicit ReplayStream(std::string name = "replay");

  // --- loading (before the replay starts) ---------------------------------
  void reserve(std::size_t events);
  // One recorded call; log_event is its event number in the log file.
  // Ignored after a hole.
  void append(const BusEvent& ev, std::int64_t log_event);
  // The recorder lost `lost` events of this thread after the last appended
  // one (its ring was full): the replay can only go that far, and the report
  // at the end says why.
  void mark_hole(std::int64_t log_event, std::uint32_t lost) { ReplayCursor::mark_hole(log_event, lost); }

  // --- replay (the stream's thread) ---------------------------------------
  // `call` carries the kind, device and arguments of the attempted call (the
  // result fields are ignored). Returns the recorded event, valid until the
  // next take(), when it is the same call; otherwise nullptr, and the
  // divergence is set (the first one wins) and every later take() fails.
  const BusEvent* take(const BusEvent& call) noexcept { return take_next(call); }

  // --- inspection (tools, tests) -------------------------------------------
  // The i-th recorded event, expanded.
  BusEvent event(std::size_t i) const noexcept;

 private:
  friend class ReplayCursor<ReplayStream, BusEvent>;
  static constexpr const char* kCallNoun = "events";
  static constexpr const char* kNothingRecorded = "recorded events";

  const BusEvent& recorded(std::size_t i) noexcept;
  // Of two calls of the same kind on the same device.
  static bool same_arguments(const BusEvent& rec, const BusEvent& call) noexcept;
  void describe_call(ReportText& t, const BusEvent& ev, bool attempted) const noexcept;
  void describe_arguments(ReportText& t, const BusEvent& ev) const noexcept;
  void describe_hole(ReportText& t, unsigned long long replayed) const noexcept;
  void expand(std::size_t i, BusEvent* out) const noexcept;

  std::vector<std::size_t> offsets_;  // of each event, into bytes_
  std::vector<std::uint8_t> bytes_;
  BusEvent current_;  // the event take() hands out, expanded
};

}  // namespace rtfuse::hal::replay
