#include "hal/replay/replay_stream.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <utility>

#include "hal/replay/report_text.hpp"

namespace rtfuse::hal::replay {
namespace {

// Everything before the frames: the fixed part every event keeps.
constexpr std::size_t kHeadBytes = offsetof(BusEvent, frames);

int stored_bytes(const BusEvent& ev) {
  switch (ev.kind) {
    case BusEventKind::kI2cRead:
    case BusEventKind::kSerialWrite: return std::clamp(ev.length, 0, kBusEventMaxBytes);
    case BusEventKind::kSerialRead: return std::min<int>(ev.count, kBusEventMaxBytes);
    default: return 0;
  }
}

int stored_frames(const BusEvent& ev) {
  return ev.kind == BusEventKind::kCanSend || ev.kind == BusEventKind::kCanReceive
             ? std::min<int>(ev.count, kBusEventMaxFrames)
             : 0;
}

bool same_frame(const CanFrame& a, const CanFrame& b) {
  if (a.id != b.id || a.extended != b.extended || a.rtr != b.rtr || a.error != b.error || a.dlc != b.dlc) {
    return false;
  }
  return std::memcmp(a.data, b.data, std::min<std::size_t>(a.dlc, sizeof a.data)) == 0;
}

// Same kind of call on the same device with the same arguments.
bool same_call(const BusEvent& rec, const BusEvent& call) {
  if (rec.kind != call.kind || rec.device != call.device) return false;
  switch (rec.kind) {
    case BusEventKind::kCanSend: return same_frame(rec.frames[0], call.frames[0]);
    case BusEventKind::kCanReceive: return rec.length == call.length && rec.timeout_ns == call.timeout_ns;
    case BusEventKind::kI2cRead:
      return rec.address == call.address && rec.reg == call.reg && rec.length == call.length;
    case BusEventKind::kI2cWrite:
      return rec.address == call.address && rec.reg == call.reg && rec.value == call.value;
    case BusEventKind::kGpioWaitEdge: return rec.timeout_ns == call.timeout_ns;
    case BusEventKind::kGpioSet: return rec.level == call.level;
    case BusEventKind::kClockNow: return true;
    case BusEventKind::kClockSleepUntil: return rec.clock_ns == call.clock_ns;
    case BusEventKind::kSerialRead: return rec.length == call.length && rec.timeout_ns == call.timeout_ns;
    case BusEventKind::kSerialWrite:
      return rec.length == call.length &&
             std::memcmp(rec.data, call.data, static_cast<std::size_t>(stored_bytes(rec))) == 0;
    case BusEventKind::kSerialReopen: return true;
    case BusEventKind::kNone: return true;
  }
  return false;
}

using Text = ReportText;

void add_frame(Text& t, const CanFrame& f) {
  t.add(f.extended ? "id 0x%08X" : "id 0x%03X", static_cast<unsigned>(f.id));
  if (f.extended) t.add(" ext");
  if (f.rtr) t.add(" rtr");
  if (f.error) t.add(" err");
  t.add(" dlc %d", f.dlc);
  const int n = std::min<int>(f.dlc, 8);
  if (n > 0 && !f.rtr) {
    t.add(" [");
    for (int i = 0; i < n; ++i) t.add(i == 0 ? "%02X" : " %02X", f.data[i]);
    t.add("]");
  }
}

}  // namespace

ReplayStream::ReplayStream(std::string name) : name_(std::move(name)) {}

void ReplayStream::reserve(std::size_t events) {
  heads_.reserve(events);
  bytes_.reserve(events * (kHeadBytes + sizeof(CanFrame)));
}

void ReplayStream::append(const BusEvent& ev, std::int64_t log_event) {
  heads_.push_back(Head{log_event, bytes_.size()});
  const auto* raw = reinterpret_cast<const std::uint8_t*>(&ev);
  bytes_.insert(bytes_.end(), raw, raw + kHeadBytes);
  const auto* frames = reinterpret_cast<const std::uint8_t*>(ev.frames);
  bytes_.insert(bytes_.end(), frames, frames + static_cast<std::size_t>(stored_frames(ev)) * sizeof(CanFrame));
  bytes_.insert(bytes_.end(), ev.data, ev.data + stored_bytes(ev));
}

void ReplayStream::mark_hole(std::int64_t log_event, std::uint32_t lost) {
  if (hole_lost_ > 0) return;  // only the first hole matters: the replay stops there
  hole_event_ = log_event;
  hole_lost_ = lost;
}

void ReplayStream::set_device_name(std::uint8_t device, std::string name) {
  if (device_names_.size() <= device) device_names_.resize(static_cast<std::size_t>(device) + 1);
  device_names_[device] = std::move(name);
}

void ReplayStream::expand(std::size_t i, BusEvent* out) const noexcept {
  *out = BusEvent{};
  const std::uint8_t* p = bytes_.data() + heads_[i].offset;
  std::memcpy(static_cast<void*>(out), p, kHeadBytes);
  p += kHeadBytes;
  const std::size_t frame_bytes = static_cast<std::size_t>(stored_frames(*out)) * sizeof(CanFrame);
  std::memcpy(static_cast<void*>(out->frames), p, frame_bytes);
  p += frame_bytes;
  std::memcpy(out->data, p, static_cast<std::size_t>(stored_bytes(*out)));
}

BusEvent ReplayStream::event(std::size_t i) const noexcept {
  BusEvent ev;
  if (i < heads_.size()) expand(i, &ev);
  return ev;
}

const BusEvent* ReplayStream::take(const BusEvent& call) noexcept {
  if (diverged()) return nullptr;
  const std::size_t pos = position_.load(std::memory_order_relaxed);
  if (pos >= heads_.size()) {
    diverge(DivergenceKind::kEndOfStream, heads_.empty() ? -1 : heads_.back().log_event, nullptr, call);
    return nullptr;
  }
  expand(pos, &current_);
  if (!same_call(current_, call)) {
    diverge(DivergenceKind::kMismatch, heads_[pos].log_event, &current_, call);
    return nullptr;
  }
  position_.store(pos + 1, std::memory_order_release);
  return &current_;
}

const char* ReplayStream::device_name(std::uint8_t device, char* scratch, std::size_t size) const noexcept {
  if (device < device_names_.size() && !device_names_[device].empty()) return device_names_[device].c_str();
  std::snprintf(scratch, size, "device %u", static_cast<unsigned>(device));
  return scratch;
}

int ReplayStream::describe(char* buf, std::size_t size, const BusEvent& ev, bool attempted,
                           bool with_device) const noexcept {
  Text t(buf, size);
  if (attempted && ev.kind == BusEventKind::kCanSend) {
    t.add("sent");
  } else if (attempted) {
    t.add("called %s", to_string(ev.kind));
  } else {
    t.add("%s", to_string(ev.kind));
  }
  if (with_device) {
    char scratch[24];
    t.add(" on %s", device_name(ev.device, scratch, sizeof scratch));
  }
  switch (ev.kind) {
    case BusEventKind::kCanSend:
      t.add(" ");
      add_frame(t, ev.frames[0]);
      break;
    case BusEventKind::kCanReceive:
      t.add(" max %d timeout %lld ns", ev.length, static_cast<long long>(ev.timeout_ns));
      break;
    case BusEventKind::kI2cRead:
      t.add(" addr 0x%02X reg 0x%02X len %d", ev.address, ev.reg, ev.length);
      break;
    case BusEventKind::kI2cWrite:
      t.add(" addr 0x%02X reg 0x%02X value 0x%02X", ev.address, ev.reg, ev.value);
      break;
    case BusEventKind::kGpioWaitEdge: t.add(" timeout %lld ns", static_cast<long long>(ev.timeout_ns)); break;
    case BusEventKind::kGpioSet: t.add(ev.level != 0 ? " high" : " low"); break;
    case BusEventKind::kClockSleepUntil: t.add(" deadline %lld ns", static_cast<long long>(ev.clock_ns)); break;
    case BusEventKind::kSerialRead:
      t.add(" max %d timeout %lld ns", ev.length, static_cast<long long>(ev.timeout_ns));
      break;
    case BusEventKind::kSerialWrite: {
      t.add(" %d bytes [", ev.length);
      const int n = std::min(stored_bytes(ev), 16);
      for (int i = 0; i < n; ++i) t.add(i == 0 ? "%02X" : " %02X", ev.data[i]);
      t.add(n < ev.length ? " ...]" : "]");
      break;
    }
    case BusEventKind::kClockNow:
    case BusEventKind::kSerialReopen:
    case BusEventKind::kNone: break;
  }
  return t.length();
}

void ReplayStream::diverge(DivergenceKind kind, std::int64_t log_event, const BusEvent* recorded,
                           const BusEvent& call) noexcept {
  char attempted[256];
  Text t(report_, sizeof report_);
  if (kind == DivergenceKind::kMismatch && recorded != nullptr) {
    const bool other_device = recorded->device != call.device;
    char rec[256];
    describe(rec, sizeof rec, *recorded, false, other_device);
    describe(attempted, sizeof attempted, call, true, other_device);
    t.add("event %lld: recorded %s, driver %s", static_cast<long long>(log_event), rec, attempted);
  } else {
    describe(attempted, sizeof attempted, call, true, true);
    const auto replayed = static_cast<unsigned long long>(heads_.size());
    if (hole_lost_ > 0) {
      t.add("stream '%s' ends at event %lld, where the recorder lost %u events (its ring was full while "
            "recording; %llu events replayed): driver %s",
            name_.c_str(), static_cast<long long>(hole_event_), hole_lost_, replayed, attempted);
    } else if (heads_.empty()) {
      t.add("stream '%s' has no recorded events: driver %s", name_.c_str(), attempted);
    } else {
      t.add("stream '%s' ended after event %lld (%llu events replayed): driver %s", name_.c_str(),
            static_cast<long long>(log_event), replayed, attempted);
    }
  }
  report_event_ = log_event;
  kind_.store(kind, std::memory_order_release);
}

}  // namespace rtfuse::hal::replay
