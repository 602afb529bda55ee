#include "hal/replay/replay_stream.hpp"

#include <algorithm>
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

void add_frame(ReportText& t, const CanFrame& f) {
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

ReplayStream::ReplayStream(std::string name) : ReplayCursor(std::move(name)) {}

void ReplayStream::reserve(std::size_t events) {
  reserve_calls(events);
  offsets_.reserve(events);
  bytes_.reserve(events * (kHeadBytes + sizeof(CanFrame)));
}

void ReplayStream::append(const BusEvent& ev, std::int64_t log_event) {
  if (!add_call(log_event)) return;
  offsets_.push_back(bytes_.size());
  const auto* raw = reinterpret_cast<const std::uint8_t*>(&ev);
  bytes_.insert(bytes_.end(), raw, raw + kHeadBytes);
  const auto* frames = reinterpret_cast<const std::uint8_t*>(ev.frames);
  bytes_.insert(bytes_.end(), frames, frames + static_cast<std::size_t>(stored_frames(ev)) * sizeof(CanFrame));
  bytes_.insert(bytes_.end(), ev.data, ev.data + stored_bytes(ev));
}

void ReplayStream::expand(std::size_t i, BusEvent* out) const noexcept {
  *out = BusEvent{};
  const std::uint8_t* p = bytes_.data() + offsets_[i];
  std::memcpy(static_cast<void*>(out), p, kHeadBytes);
  p += kHeadBytes;
  const std::size_t frame_bytes = static_cast<std::size_t>(stored_frames(*out)) * sizeof(CanFrame);
  std::memcpy(static_cast<void*>(out->frames), p, frame_bytes);
  p += frame_bytes;
  std::memcpy(out->data, p, static_cast<std::size_t>(stored_bytes(*out)));
}

BusEvent ReplayStream::event(std::size_t i) const noexcept {
  BusEvent ev;
  if (i < offsets_.size()) expand(i, &ev);
  return ev;
}

const BusEvent& ReplayStream::recorded(std::size_t i) noexcept {
  expand(i, &current_);
  return current_;
}

bool ReplayStream::same_arguments(const BusEvent& rec, const BusEvent& call) noexcept {
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

void ReplayStream::describe_call(ReportText& t, const BusEvent& ev, bool attempted) const noexcept {
  if (attempted && ev.kind == BusEventKind::kCanSend) {
    t.add("sent");
  } else {
    t.add(attempted ? "called %s" : "%s", to_string(ev.kind));
  }
}

void ReplayStream::describe_arguments(ReportText& t, const BusEvent& ev) const noexcept {
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
}

void ReplayStream::describe_hole(ReportText& t, unsigned long long replayed) const noexcept {
  describe_lost_calls(t, replayed, "");
}

}  // namespace rtfuse::hal::replay
