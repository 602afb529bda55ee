#pragma once
// The divergence rules of a replay, in one place for every kind of recorded
// call: bus events (ReplayStream) and camera calls (ReplayVideoLog) must stop
// a replay for the same reasons and say so in the same words, and two copies
// of the rules would drift apart.
//
// The rules:
// - the next recorded call is handed back only when the attempted call is
//   the same kind on the same device with the same arguments;
// - else the replay has diverged: the first divergence wins, and every later
//   take fails, even for the call that was recorded;
// - a call after the last recorded one is an end-of-stream divergence, which
//   at_end() still counts as a clean stop;
// - a hole (the recorder's ring was full, mark_hole) ends the stream there:
//   calls appended after it are dropped, and the end-of-stream report says
//   why the stream is short;
// - a report names the log event, the recorded call and the attempted call.
//
// ReplayCursor owns the position, the divergence, its report and the hole;
// each stream (CRTP: class Log : public ReplayCursor<Log, Event>) stores its
// calls and supplies, as members the cursor may call (a friend):
//   const Event& recorded(std::size_t i) noexcept;  valid until the next call
//   static bool same_arguments(const Event& recorded, const Event& call) noexcept;
//     of two calls of the same kind on the same device
//   void describe_call(ReportText&, const Event&, bool attempted) const noexcept;
//     the call's name ("called dequeue"); the cursor adds " on <device>"
//   void describe_arguments(ReportText&, const Event&) const noexcept;
//   void describe_hole(ReportText&, unsigned long long replayed) const noexcept;
//     what follows "stream 'x' ends at event N" (describe_lost_calls helps)
//   static constexpr const char* kCallNoun;         "events", "calls"
//   static constexpr const char* kNothingRecorded;  "recorded events"
// Event has `kind` (of call) and `device` (the recorded device index).
//
// Loading (append, names, holes) may allocate and happens before the replay
// starts. take_next() and everything the replay thread calls never allocate,
// lock or block: the report is written into fixed storage. One thread
// replays a stream; diverged(), position() and the report may be read from
// any other thread (the report once diverged() is true: it is written before
// the kind is stored with release, and read after an acquire load).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hal/replay/report_text.hpp"

namespace rtfuse::hal::replay {

enum class DivergenceKind : std::uint8_t {
  kNone,
  kMismatch,     // a call that is not the recorded one
  kEndOfStream,  // a call after the last recorded one (or past a hole in the recording)
};

template <class Log, class Event>
class ReplayCursor {
 public:
  static constexpr std::size_t kReportSize = 512;

  ReplayCursor(const ReplayCursor&) = delete;
  ReplayCursor& operator=(const ReplayCursor&) = delete;

  // --- loading (before the replay starts) ---------------------------------
  // Names reports use for device indices ("can0"); "device N" otherwise.
  void set_device_name(std::uint8_t device, std::string name) {
    if (device_names_.size() <= device) device_names_.resize(static_cast<std::size_t>(device) + 1);
    device_names_[device] = std::move(name);
  }

  // --- replay state (any thread) ------------------------------------------
  bool diverged() const noexcept { return divergence_kind() != DivergenceKind::kNone; }
  DivergenceKind divergence_kind() const noexcept { return kind_.load(std::memory_order_acquire); }
  // The report ("" until diverged).
  const char* divergence() const noexcept { return diverged() ? report_ : ""; }
  // Log event number the report is about (the recorded call that did not
  // match, or the last one replayed at the end of the stream); -1 if none.
  std::int64_t divergence_event() const noexcept { return diverged() ? report_event_ : -1; }
  // Every recorded call was replayed and none differed: a clean stop, even if
  // a driver then tried one more call.
  bool at_end() const noexcept { return position() == size() && divergence_kind() != DivergenceKind::kMismatch; }
  std::size_t position() const noexcept { return position_.load(std::memory_order_acquire); }
  std::size_t size() const noexcept { return log_events_.size(); }
  std::size_t remaining() const noexcept { return size() - position(); }

  // --- inspection (tools, tests) -------------------------------------------
  const std::string& name() const { return name_; }
  // The log event number of the i-th recorded call.
  std::int64_t log_event(std::size_t i) const noexcept { return log_events_[i]; }
  bool has_hole() const noexcept { return hole_lost_ > 0; }
  std::int64_t hole_event() const noexcept { return hole_event_; }

 protected:
  explicit ReplayCursor(std::string name) : name_(std::move(name)) {}
  ~ReplayCursor() = default;

  void reserve_calls(std::size_t calls) { log_events_.reserve(calls); }
  // Registers the next recorded call; false after a hole, where the stream
  // ends (the caller then keeps nothing of it).
  bool add_call(std::int64_t log_event) {
    if (has_hole()) return false;
    log_events_.push_back(log_event);
    return true;
  }
  // The recorder lost `lost` calls after the last added one. Only the first
  // hole matters (the replay stops there): false for any later one.
  bool mark_hole(std::int64_t log_event, std::uint32_t lost) noexcept {
    if (has_hole()) return false;
    hole_event_ = log_event;
    hole_lost_ = lost;
    return true;
  }
  std::uint32_t hole_lost() const noexcept { return hole_lost_; }

  // The take/diverge sequence: the next recorded call when `call` is the
  // same (and *taken its index), else nullptr with the divergence set.
  const Event* take_next(const Event& call, std::size_t* taken = nullptr) noexcept {
    if (diverged()) return nullptr;
    const std::size_t pos = position_.load(std::memory_order_relaxed);
    if (pos >= size()) {
      diverge(DivergenceKind::kEndOfStream, log_events_.empty() ? -1 : log_events_.back(), nullptr, call);
      return nullptr;
    }
    const Event& rec = self().recorded(pos);
    if (rec.kind != call.kind || rec.device != call.device || !Log::same_arguments(rec, call)) {
      diverge(DivergenceKind::kMismatch, log_events_[pos], &rec, call);
      return nullptr;
    }
    if (taken != nullptr) *taken = pos;
    position_.store(pos + 1, std::memory_order_release);
    return &rec;
  }

  // The usual hole text, ", where the recorder lost 3 events (its ring was
  // full ...)", with `note` inside the parentheses first.
  void describe_lost_calls(ReportText& t, unsigned long long replayed, const char* note) const noexcept {
    t.add(", where the recorder lost %u %s (%sits ring was full while recording; %llu %s replayed)", hole_lost_,
          Log::kCallNoun, note, replayed, Log::kCallNoun);
  }

 private:
  Log& self() noexcept { return static_cast<Log&>(*this); }
  const Log& self() const noexcept { return static_cast<const Log&>(*this); }

  void describe(ReportText& t, const Event& ev, bool attempted, bool with_device) const noexcept {
    self().describe_call(t, ev, attempted);
    if (with_device) {
      if (ev.device < device_names_.size() && !device_names_[ev.device].empty()) {
        t.add(" on %s", device_names_[ev.device].c_str());
      } else {
        t.add(" on device %u", static_cast<unsigned>(ev.device));
      }
    }
    self().describe_arguments(t, ev);
  }

  // recorded: the call that did not match (a mismatch), null at the end.
  void diverge(DivergenceKind kind, std::int64_t log_event, const Event* recorded, const Event& call) noexcept {
    ReportText t(report_, sizeof report_);
    if (recorded != nullptr) {
      // The device is named only when it differs: on one device the call says it all.
      const bool other_device = recorded->device != call.device;
      t.add("event %lld: recorded ", static_cast<long long>(log_event));
      describe(t, *recorded, false, other_device);
      t.add(", driver ");
      describe(t, call, true, other_device);
    } else {
      const auto replayed = static_cast<unsigned long long>(size());
      if (has_hole()) {
        t.add("stream '%s' ends at event %lld", name_.c_str(), static_cast<long long>(hole_event_));
        self().describe_hole(t, replayed);
      } else if (size() == 0) {
        t.add("stream '%s' has no %s", name_.c_str(), Log::kNothingRecorded);
      } else {
        t.add("stream '%s' ended after event %lld (%llu %s replayed)", name_.c_str(),
              static_cast<long long>(log_event), replayed, Log::kCallNoun);
      }
      t.add(": driver ");
      describe(t, call, true, true);
    }
    report_event_ = log_event;
    kind_.store(kind, std::memory_order_release);
  }

  std::string name_;
  std::vector<std::int64_t> log_events_;  // of each recorded call, in call order
  std::vector<std::string> device_names_;
  std::int64_t hole_event_ = -1;
  std::uint32_t hole_lost_ = 0;

  std::atomic<std::size_t> position_{0};
  std::atomic<DivergenceKind> kind_{DivergenceKind::kNone};
  std::int64_t report_event_ = -1;
  char report_[kReportSize] = {};
};

}  // namespace rtfuse::hal::replay
