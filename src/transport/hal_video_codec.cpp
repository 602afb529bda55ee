#include "transport/hal_video_codec.hpp"

#include <algorithm>
#include <limits>

#include "rtfuse/hal_video_t.hpp"
#include "transport/encode_buffer.hpp"
#include "transport/record_decoding.hpp"
#include "transport/recording_info.hpp"

namespace rtfuse::transport {

using decoding::after_device_string;
using decoding::bad_field;
using decoding::count_within;
using decoding::decode_message;
using decoding::set_error;
using decoding::valid_status;
using hal::HalStatus;

namespace {

std::int8_t video_call(hal::VideoCallKind k) {
  switch (k) {
    case hal::VideoCallKind::kDequeue: return rtfuse::hal_video_t::DEQUEUE;
    case hal::VideoCallKind::kRelease: return rtfuse::hal_video_t::RELEASE;
    case hal::VideoCallKind::kStart: return rtfuse::hal_video_t::START;
    case hal::VideoCallKind::kStop: return rtfuse::hal_video_t::STOP;
    case hal::VideoCallKind::kReopen: return rtfuse::hal_video_t::REOPEN;
    case hal::VideoCallKind::kNone: break;
  }
  return -1;
}

bool in_u32(std::int64_t v) { return v >= 0 && v <= std::numeric_limits<std::uint32_t>::max(); }

}  // namespace

HalVideoCodec::HalVideoCodec() : msg_(std::make_unique<rtfuse::hal_video_t>()) {
  // Capacity up front, so encoding stops allocating once the name was used.
  msg_->device.reserve(kMaxDeviceNameLength);
}

HalVideoCodec::~HalVideoCodec() = default;

int HalVideoCodec::encode(const std::string& device, const hal::VideoEvent& ev, const std::uint8_t* data,
                          std::uint8_t* buf, int capacity) {
  const std::int8_t call = video_call(ev.kind);
  if (call < 0) return -1;
  const bool frame = ev.has_frame();
  if (frame && ev.data_size > 0 && data == nullptr) return -1;
  // A frame never fits an int-sized LCM message past 2 GB; nothing real comes close.
  if (ev.data_size > static_cast<std::uint32_t>(std::numeric_limits<std::int32_t>::max() - kVideoRecordOverhead)) {
    return -1;
  }
  rtfuse::hal_video_t& m = *msg_;
  m.utime = ns_to_utime(ev.time_ns);
  m.time_ns = ev.time_ns;
  m.device = device;
  m.call = call;
  m.status = static_cast<std::int8_t>(ev.status);
  m.timeout_ns = ev.timeout_ns;
  m.buffer_index = ev.index;
  m.stamp_ns = ev.stamp;
  m.sequence = ev.sequence;
  m.bytes_used = ev.bytes_used;
  m.buffer_length = ev.length;
  m.corrupted = ev.corrupted != 0;
  m.frame_number = ev.frames_before;
  m.lost_before = static_cast<std::int32_t>(std::min<std::uint32_t>(ev.lost_before, 0x7FFFFFFF));
  m.pixel_format = ev.pixel_format;
  m.width = ev.width;
  m.height = ev.height;
  m.bytes_per_line = ev.bytes_per_line;
  m.image_size = ev.image_size;
  m.fps_numerator = ev.fps_numerator;
  m.fps_denominator = ev.fps_denominator;
  m.buffers = ev.buffers;
  const std::uint32_t n = frame ? ev.data_size : 0;
  m.num_data = static_cast<std::int32_t>(n);
  m.data.assign(data, data + n);  // keeps its capacity: allocates until the largest frame was seen
  return encode_into(m, buf, capacity);
}

bool HalVideoCodec::decode(std::uint8_t device, const std::string& name, const void* data, int size,
                           hal::VideoEvent* out, const std::uint8_t** frame, std::string* error) {
  constexpr const char* kType = "hal_video_t";
  if (frame != nullptr) *frame = nullptr;
  const auto* b = static_cast<const std::uint8_t*>(data);
  const int after_name = b == nullptr ? -1 : after_device_string(b, size);
  // call .. buffers (see hal_video_t.lcm): 107 bytes to num_data. num_data
  // must fit in what is left, so a truncated or corrupt frame record is
  // refused before lcm-gen sizes a vector from it.
  const int at = after_name < 0 ? -1 : after_name + 107;
  if (at < 0 || !count_within(b, size, at, size - at - 4)) {
    set_error(error, "malformed hal_video_t of " + std::to_string(size) +
                         " bytes: too short, or a frame length past the end of the record (truncated?)");
    return false;
  }
  rtfuse::hal_video_t& m = *msg_;
  if (!decode_message(m, data, size, kType, error)) return false;
  if (m.device != name) {
    set_error(error, std::string(kType) + " names device '" + m.device + "' on the channel of '" + name + "'");
    return false;
  }
  if (!valid_status(m.status)) return bad_field(error, kType, "status", m.status);
  hal::VideoEvent ev;
  switch (m.call) {
    case rtfuse::hal_video_t::DEQUEUE: ev.kind = hal::VideoCallKind::kDequeue; break;
    case rtfuse::hal_video_t::RELEASE: ev.kind = hal::VideoCallKind::kRelease; break;
    case rtfuse::hal_video_t::START: ev.kind = hal::VideoCallKind::kStart; break;
    case rtfuse::hal_video_t::STOP: ev.kind = hal::VideoCallKind::kStop; break;
    case rtfuse::hal_video_t::REOPEN: ev.kind = hal::VideoCallKind::kReopen; break;
    default: return bad_field(error, kType, "call", m.call);
  }
  ev.device = device;
  ev.status = static_cast<HalStatus>(m.status);
  const bool has_frame = ev.has_frame();
  if (has_frame) {
    if (m.buffer_index < 0 || m.buffer_index >= hal::kMaxVideoBuffers) {
      return bad_field(error, kType, "buffer index", m.buffer_index);
    }
    if (!in_u32(m.sequence)) return bad_field(error, kType, "sequence", m.sequence);
    if (!in_u32(m.bytes_used)) return bad_field(error, kType, "bytes_used", m.bytes_used);
    if (!in_u32(m.buffer_length)) return bad_field(error, kType, "buffer_length", m.buffer_length);
    if (m.num_data > std::min(m.bytes_used, m.buffer_length)) {
      return bad_field(error, kType, "frame byte count (above bytes_used or the buffer)", m.num_data);
    }
  } else if (m.num_data != 0 || m.bytes_used != 0 || m.buffer_length != 0 || m.sequence != 0 || m.stamp_ns != 0 ||
             m.corrupted) {
    return bad_field(error, kType, "frame field on a call that returned no frame; frame bytes", m.num_data);
  }
  if (m.frame_number < 0) return bad_field(error, kType, "frame_number", m.frame_number);
  if (m.lost_before < 0) return bad_field(error, kType, "lost_before", m.lost_before);
  if (!in_u32(m.pixel_format) || !in_u32(m.image_size) || !in_u32(m.fps_numerator) || !in_u32(m.fps_denominator)) {
    return bad_field(error, kType, "format field (pixel format, image size or rate)", m.pixel_format);
  }
  ev.time_ns = m.time_ns;
  ev.timeout_ns = m.timeout_ns;
  ev.index = m.buffer_index;
  ev.stamp = m.stamp_ns;
  ev.sequence = static_cast<std::uint32_t>(m.sequence);
  ev.bytes_used = static_cast<std::uint32_t>(m.bytes_used);
  ev.length = static_cast<std::uint32_t>(m.buffer_length);
  ev.data_size = static_cast<std::uint32_t>(m.num_data);
  ev.corrupted = m.corrupted ? 1 : 0;
  ev.frames_before = m.frame_number;
  ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
  ev.pixel_format = static_cast<std::uint32_t>(m.pixel_format);
  ev.width = m.width;
  ev.height = m.height;
  ev.bytes_per_line = m.bytes_per_line;
  ev.image_size = static_cast<std::uint32_t>(m.image_size);
  ev.fps_numerator = static_cast<std::uint32_t>(m.fps_numerator);
  ev.fps_denominator = static_cast<std::uint32_t>(m.fps_denominator);
  ev.buffers = m.buffers;
  *out = ev;
  if (frame != nullptr && has_frame && m.num_data > 0) *frame = m.data.data();
  return true;
}

}  // namespace rtfuse::transport
