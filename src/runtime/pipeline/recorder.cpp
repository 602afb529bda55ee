#include "runtime/pipeline/recorder.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <system_error>
#include <utility>

namespace rtfuse::runtime {
namespace {

// Records per ring per pass: bounds how long one busy ring can starve the others.
constexpr int kBatch = 256;
// Video records per ring per pass: one can be a 1 MB frame, so fewer, or the
// bus rings would wait for a whole batch of frames to reach the disk.
constexpr int kVideoBatch = 8;

void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

}  // namespace

Recorder::Recorder(transport::RecordingInfo info, const RecorderRingSizes& sizes)
    : info_(std::move(info)),
      codec_(info_.devices),
      ticks_(sizes.ticks > 0 ? sizes.ticks : 1),
      outputs_(sizes.outputs > 0 ? sizes.outputs : 1),
      inputs_(64),
      bus_lost_(new std::atomic<std::int64_t>[info_.streams.size()]) {
  for (std::size_t i = 0; i < info_.streams.size(); ++i) {
    rings_.push_back(std::make_unique<SpscRing<hal::BusEvent>>(sizes.bus_events > 0 ? sizes.bus_events : 1));
    bus_lost_[i].store(0);
  }
}

std::unique_ptr<Recorder> Recorder::create(const std::string& path, transport::RecordingInfo info,
                                           const RecorderRingSizes& sizes, std::string* error) {
  if (!transport::validate(info, error)) return nullptr;
  info.format_version = transport::kHalRecordFormatVersion;
  if (info.start_ns == 0) info.start_ns = monotonic_now_ns();
  info.config_hash = transport::config_text_hash(info.config_text);
  std::unique_ptr<Recorder> rec(new Recorder(std::move(info), sizes));
  std::string why;
  if (!rec->writer_.open(path, &why)) {
    set_error(error, "recording: " + why);
    return nullptr;
  }
  const std::vector<std::uint8_t> bytes = transport::encode_recording_info(rec->info_);
  rec->write(ns_to_utime(rec->info_.start_ns), transport::kRecordingInfoChannel, bytes.data(), bytes.size());
  for (const transport::RecordedFile& f : rec->info_.files) {
    const std::vector<std::uint8_t> file = transport::encode_recorded_file(f);
    rec->write(ns_to_utime(rec->info_.start_ns), transport::kRecordedFileChannel, file.data(), file.size());
  }
  // On disk at once: a recorder killed before its first flush still leaves a
  // file that says what it is.
  if (rec->write_errors_.load() > 0 || !rec->writer_.flush(&why)) {
    set_error(error, "recording " + path + ": " + (rec->first_error_.empty() ? why : rec->first_error_));
    return nullptr;
  }
  return rec;
}

Recorder::~Recorder() { stop(); }

int Recorder::stream_index(std::string_view name) const {
  for (std::size_t i = 0; i < info_.streams.size(); ++i) {
    if (info_.streams[i] == name) return static_cast<int>(i);
  }
  return -1;
}

hal::VideoRecordRing* Recorder::add_video_ring(int stream, std::size_t slot_bytes, std::size_t frame_slots,
                                               std::size_t events, std::string* error) {
  if (thread_.joinable() || stopped_) {
    set_error(error, "recording: add_video_ring after the recorder started");
    return nullptr;
  }
  if (stream < 0 || stream >= stream_count()) {
    set_error(error, "recording: add_video_ring: stream " + std::to_string(stream) + " does not exist");
    return nullptr;
  }
  bool has_video = false;
  for (const transport::RecordedDevice& d : info_.devices) {
    if (d.stream == stream && d.kind == transport::DeviceKind::kVideo) has_video = true;
  }
  if (!has_video) {
    set_error(error, "recording: stream '" + info_.streams[static_cast<std::size_t>(stream)] +
                         "' has no video device in the recording info");
    return nullptr;
  }
  for (const VideoRing& v : video_rings_) {
    if (v.stream == stream) {
      set_error(error, "recording: stream '" + info_.streams[static_cast<std::size_t>(stream)] +
                           "' already has a video ring");
      return nullptr;
    }
  }
  constexpr std::size_t kMaxSlotBytes = 256u << 20;  // far above any frame; keeps the record an LCM int size
  if (slot_bytes == 0 || slot_bytes > kMaxSlotBytes || frame_slots == 0) {
    set_error(error, "recording: add_video_ring: slot_bytes " + std::to_string(slot_bytes) + " and frame_slots " +
                         std::to_string(frame_slots) + " (need 1.." + std::to_string(kMaxSlotBytes) +
                         " bytes, at least one slot)");
    return nullptr;
  }
  if (events == 0) events = 4 * frame_slots + 64;
  VideoRing v;
  v.stream = stream;
  v.ring = std::make_unique<hal::VideoRecordRing>(slot_bytes, frame_slots, events);
  const std::size_t need = slot_bytes + static_cast<std::size_t>(transport::kVideoRecordOverhead);
  if (video_buf_.size() < need) video_buf_.resize(need);
  video_rings_.push_back(std::move(v));
  return video_rings_.back().ring.get();
}

bool Recorder::backlogged() const noexcept {
  for (const auto& r : rings_) {
    if (2 * r->size() > r->capacity()) return true;
  }
  for (const VideoRing& v : video_rings_) {
    if (2 * v.ring->frames() > v.ring->frame_capacity() || 2 * v.ring->events() > v.ring->event_capacity()) {
      return true;
    }
  }
  return 2 * ticks_.size() > ticks_.capacity() || 2 * outputs_.size() > outputs_.capacity();
}

bool Recorder::record_tick(TimeNs t, std::uint64_t seq, const std::int64_t* consumed, int n,
                           std::uint32_t published) noexcept {
  if (n < 0 || n > kMaxTickSensors || (n > 0 && consumed == nullptr)) {
    ticks_rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  tick_staging_.time_ns = t;
  tick_staging_.seq = static_cast<std::int64_t>(seq);
  tick_staging_.n = n;
  tick_staging_.published = published;
  for (int i = 0; i < n; ++i) tick_staging_.consumed[i] = consumed[i];
  if (!ticks_.try_push(tick_staging_)) {
    ticks_lost_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

bool Recorder::record_output(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept {
  const std::size_t channel_length = channel == nullptr ? 0 : std::strlen(channel);
  if (channel_length == 0 || channel_length > kMaxChannelLength || size < 0 || size > kMaxOutputBytes ||
      (size > 0 && data == nullptr)) {
    outputs_rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  output_staging_.now = now;
  output_staging_.size = size;
  output_staging_.channel.assign(std::string_view(channel, channel_length));
  if (size > 0) std::memcpy(output_staging_.data, data, static_cast<std::size_t>(size));
  if (!outputs_.try_push(output_staging_)) {
    outputs_lost_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

bool Recorder::record_input(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept {
  const std::size_t channel_length = channel == nullptr ? 0 : std::strlen(channel);
  constexpr std::size_t kPrefix = transport::kRecordedInputPrefix.size();
  if (channel_length == 0 || channel_length + kPrefix > kMaxChannelLength || size < 0 || size > kMaxOutputBytes ||
      (size > 0 && data == nullptr)) {
    inputs_rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  input_staging_.now = now;
  input_staging_.size = size;
  char name[kMaxChannelLength + 1];
  std::memcpy(name, transport::kRecordedInputPrefix.data(), kPrefix);
  std::memcpy(name + kPrefix, channel, channel_length);
  input_staging_.channel.assign(std::string_view(name, kPrefix + channel_length));
  if (size > 0) std::memcpy(input_staging_.data, data, static_cast<std::size_t>(size));
  if (!inputs_.try_push(input_staging_)) {
    inputs_lost_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

bool Recorder::start(std::string* error) {
  if (thread_.joinable() || stopped_) {
    set_error(error, "recording: the recorder was already started");
    return false;
  }
  try {
    thread_ = std::thread([this] { run(); });
  } catch (const std::system_error& e) {
    set_error(error, std::string("recording: cannot start the rtfuse-rec thread: ") + e.what());
    return false;
  }
  return true;
}

bool Recorder::stop(std::string* error) {
  if (!stopped_) {
    stopped_ = true;
    stop_requested_.store(true, std::memory_order_release);
    if (thread_.joinable()) {
      thread_.join();
    } else {
      // Never started: what was queued is still written.
      while (drain_once() > 0) {
      }
    }
    // Last, the end record: a log without it was cut short, even between
    // two events. Stamped with the newest event's time, not the clock, so
    // a lockstep simulation records the same bytes every run.
    std::int64_t lost = ticks_lost_.load() + outputs_lost_.load() + inputs_lost_.load() + write_errors_.load();
    for (std::size_t i = 0; i < info_.streams.size(); ++i) lost += bus_lost_[i].load();
    const std::vector<std::uint8_t> end =
        transport::encode_recording_end({utime_to_ns(last_utime_), writer_.events_written(), lost});
    write(last_utime_, transport::kRecordingEndChannel, end.data(), end.size());
    std::string why;
    if (!writer_.close(&why)) {
      write_errors_.fetch_add(1, std::memory_order_relaxed);
      if (first_error_.empty()) {
        first_error_ = why;
        failed_.store(true, std::memory_order_release);
      }
    }
  }
  if (!first_error_.empty()) {
    set_error(error, first_error_);
    return false;
  }
  return true;
}

void Recorder::run() noexcept {
  pthread_setname_np(pthread_self(), "rtfuse-rec");
  for (;;) {
    // Read before draining: once stop is seen, one more pass that finds every
    // ring empty means nothing was left behind.
    const bool stopping = stop_requested_.load(std::memory_order_acquire);
    if (drain_once() > 0) continue;
    if (stopping) break;
    std::this_thread::sleep_for(std::chrono::nanoseconds(kIdleSleepNs));
  }
}

void Recorder::write(std::int64_t utime, std::string_view channel, const std::uint8_t* data,
                     std::size_t size) noexcept {
  std::string why;
  bool ok = false;
  try {
    ok = writer_.write(utime, channel, data, size, &why);
  } catch (const std::exception& e) {
    // Only the error text can allocate; a recorder must not take rtfused down.
    why = e.what();
  }
  if (!ok) {
    write_errors_.fetch_add(1, std::memory_order_relaxed);
    if (first_error_.empty()) {
      first_error_ = why;
      failed_.store(true, std::memory_order_release);  // first_error_ never changes after this
    }
    return;
  }
  events_written_.fetch_add(1, std::memory_order_relaxed);
  last_utime_ = std::max(last_utime_, utime);
  bytes_written_.fetch_add(static_cast<std::int64_t>(transport::kEventHeaderSize + channel.size() + size),
                           std::memory_order_relaxed);
}

bool Recorder::failed(std::string* why) const {
  if (!failed_.load(std::memory_order_acquire)) return false;
  if (why != nullptr) *why = first_error_;
  return true;
}

std::size_t Recorder::drain_once() noexcept {
  std::size_t written = 0;
  std::uint8_t buf[transport::kMaxHalRecordSize];
  for (std::size_t s = 0; s < rings_.size(); ++s) {
    SpscRing<hal::BusEvent>& ring = *rings_[s];
    for (int i = 0; i < kBatch; ++i) {
      const hal::BusEvent* ev = ring.peek();
      if (ev == nullptr) break;
      if (ev->lost_before > 0) bus_lost_[s].fetch_add(ev->lost_before, std::memory_order_relaxed);
      int n = -1;
      try {
        n = codec_.encode(*ev, buf, static_cast<int>(sizeof buf));
      } catch (const std::exception&) {
        n = -1;
      }
      if (n < 0) {
        encode_errors_.fetch_add(1, std::memory_order_relaxed);
      } else {
        const TimeNs t = ev->time_ns != 0 ? ev->time_ns : monotonic_now_ns();
        write(ns_to_utime(t), codec_.channel(ev->device), buf, static_cast<std::size_t>(n));
      }
      ring.pop();
      ++written;
    }
  }
  for (VideoRing& v : video_rings_) {
    for (int i = 0; i < kVideoBatch; ++i) {
      const std::uint8_t* frame = nullptr;
      const hal::VideoEvent* ev = v.ring->peek(&frame);
      if (ev == nullptr) break;
      if (ev->lost_before > 0) {
        bus_lost_[static_cast<std::size_t>(v.stream)].fetch_add(ev->lost_before, std::memory_order_relaxed);
      }
      if (ev->frames_before > v.next_frame) {
        video_frames_lost_.fetch_add(ev->frames_before - v.next_frame, std::memory_order_relaxed);
      }
      v.next_frame = ev->frames_before + (ev->has_frame() ? 1 : 0);
      int n = -1;
      try {
        n = codec_.encode_video(*ev, frame, video_buf_.data(), static_cast<int>(video_buf_.size()));
      } catch (const std::exception&) {
        n = -1;  // the codec's first encode of the largest frame allocates
      }
      if (n < 0) {
        encode_errors_.fetch_add(1, std::memory_order_relaxed);
      } else {
        const TimeNs t = ev->time_ns != 0 ? ev->time_ns : monotonic_now_ns();
        write(ns_to_utime(t), codec_.channel(ev->device), video_buf_.data(), static_cast<std::size_t>(n));
        if (ev->has_frame()) video_frames_written_.fetch_add(1, std::memory_order_relaxed);
      }
      v.ring->pop();
      ++written;
    }
  }
  for (int i = 0; i < kBatch; ++i) {
    const TickSlot* tick = ticks_.peek();
    if (tick == nullptr) break;
    int n = -1;
    try {
      n = codec_.encode_tick(tick->time_ns, tick->seq, tick->consumed, tick->n, tick->published, buf,
                             static_cast<int>(sizeof buf));
    } catch (const std::exception&) {
      n = -1;
    }
    if (n < 0) {
      encode_errors_.fetch_add(1, std::memory_order_relaxed);
    } else {
      write(ns_to_utime(tick->time_ns), transport::kLoopTickChannel, buf, static_cast<std::size_t>(n));
    }
    ticks_.pop();
    ++written;
  }
  for (int i = 0; i < kBatch; ++i) {
    const OutputSlot* out = outputs_.peek();
    if (out == nullptr) break;
    write(ns_to_utime(out->now), out->channel.view(), out->data, static_cast<std::size_t>(out->size));
    outputs_.pop();
    ++written;
  }
  for (int i = 0; i < kBatch; ++i) {
    const OutputSlot* in = inputs_.peek();
    if (in == nullptr) break;
    write(ns_to_utime(in->now), in->channel.view(), in->data, static_cast<std::size_t>(in->size));
    inputs_.pop();
    ++written;
  }
  return written;
}

RecorderStats Recorder::stats() const {
  RecorderStats s;
  s.events_written = events_written_.load(std::memory_order_relaxed);
  s.bytes_written = bytes_written_.load(std::memory_order_relaxed);
  s.write_errors = write_errors_.load(std::memory_order_relaxed);
  s.encode_errors = encode_errors_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < rings_.size(); ++i) {
    s.bus_events_lost.push_back(bus_lost_[i].load(std::memory_order_relaxed));
  }
  s.ticks_lost = ticks_lost_.load(std::memory_order_relaxed);
  s.ticks_rejected = ticks_rejected_.load(std::memory_order_relaxed);
  s.outputs_lost = outputs_lost_.load(std::memory_order_relaxed);
  s.outputs_rejected = outputs_rejected_.load(std::memory_order_relaxed);
  s.inputs_lost = inputs_lost_.load(std::memory_order_relaxed);
  s.inputs_rejected = inputs_rejected_.load(std::memory_order_relaxed);
  s.video_frames_written = video_frames_written_.load(std::memory_order_relaxed);
  s.video_frames_lost = video_frames_lost_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace rtfuse::runtime
