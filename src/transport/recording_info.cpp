#include "transport/recording_info.hpp"

#include <string_view>
#include <utility>

#include "rtfuse/recording_end_t.hpp"
#include "rtfuse/recording_file_t.hpp"
#include "rtfuse/recording_info_t.hpp"
#include "transport/lcm_wire.hpp"
#include "transport/record_decoding.hpp"

namespace rtfuse::transport {

using hal::BusEventKind;

using decoding::bad_field;
using decoding::count_within;
using decoding::decode_message;
using decoding::set_error;
using wire::load_i32;

const char* to_string(DeviceKind k) noexcept {
  switch (k) {
    case DeviceKind::kCan: return "can";
    case DeviceKind::kI2c: return "i2c";
    case DeviceKind::kGpioEdge: return "gpio-edge";
    case DeviceKind::kGpioOutput: return "gpio-output";
    case DeviceKind::kClock: return "clock";
    case DeviceKind::kVideo: return "video";
    case DeviceKind::kSerial: return "serial";
  }
  return "unknown";
}

bool records(DeviceKind device, BusEventKind call) noexcept {
  switch (device) {
    case DeviceKind::kCan: return call == BusEventKind::kCanSend || call == BusEventKind::kCanReceive;
    case DeviceKind::kI2c: return call == BusEventKind::kI2cRead || call == BusEventKind::kI2cWrite;
    case DeviceKind::kGpioEdge: return call == BusEventKind::kGpioWaitEdge;
    case DeviceKind::kGpioOutput: return call == BusEventKind::kGpioSet;
    case DeviceKind::kClock: return call == BusEventKind::kClockNow || call == BusEventKind::kClockSleepUntil;
    case DeviceKind::kVideo: return false;  // hal_video_t, through HalRecordCodec::encode_video
    case DeviceKind::kSerial:
      return call == BusEventKind::kSerialRead || call == BusEventKind::kSerialWrite ||
             call == BusEventKind::kSerialReopen;
  }
  return false;
}

std::int64_t config_text_hash(std::string_view text) noexcept {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ull;
  }
  return static_cast<std::int64_t>(h);
}

namespace {

// LCM strings end at their first NUL (lcm-gen's encoder uses strlen()):
// one inside would write a record its own reader refuses.
bool without_nul(const std::string& s, const std::string& what, std::string* error) {
  const std::size_t at = s.find('\0');
  if (at == std::string::npos) return true;
  set_error(error, "recording info: " + what + " has a NUL byte at offset " + std::to_string(at) +
                       " (an LCM string cannot hold one)");
  return false;
}

bool valid_file(const RecordedFile& f, std::string* error) {
  if (!without_nul(f.key, "a recorded file's key", error) ||
      !without_nul(f.path, "recorded file '" + f.key + "''s path", error)) {
    return false;
  }
  if (f.key.empty() || f.key.size() > kMaxRecordedFileKeyLength || f.path.size() > kMaxRecordedFilePathLength ||
      f.text.size() > kMaxRecordedFileBytes) {
    set_error(error, "recorded file '" + f.key.substr(0, kMaxRecordedFileKeyLength) + "': key of " +
                         std::to_string(f.key.size()) + " characters (1.." +
                         std::to_string(kMaxRecordedFileKeyLength) + "), path of " + std::to_string(f.path.size()) +
                         " (at most " + std::to_string(kMaxRecordedFilePathLength) + "), " +
                         std::to_string(f.text.size()) + " bytes (at most " + std::to_string(kMaxRecordedFileBytes) +
                         ")");
    return false;
  }
  return true;
}

}  // namespace

bool validate(const RecordingInfo& info, std::string* error) {
  if (!without_nul(info.rtfuse_version, "the rtfuse version", error) ||
      !without_nul(info.config_path, "the configuration path", error) ||
      !without_nul(info.config_text, "the configuration text", error)) {
    return false;
  }
  for (const std::string& stream : info.streams) {
    if (!without_nul(stream, "a stream name", error)) return false;
  }
  const auto n_streams = static_cast<int>(info.streams.size());
  if (n_streams < 1 || n_streams > kMaxRecordedStreams) {
    set_error(error, "recording info: " + std::to_string(n_streams) + " streams (expected 1.." +
                         std::to_string(kMaxRecordedStreams) + ", one per thread that uses recorded devices)");
    return false;
  }
  if (info.devices.size() > static_cast<std::size_t>(kMaxRecordedDevices)) {
    set_error(error, "recording info: " + std::to_string(info.devices.size()) + " devices (at most " +
                         std::to_string(kMaxRecordedDevices) + ")");
    return false;
  }
  for (std::size_t i = 0; i < info.devices.size(); ++i) {
    const RecordedDevice& d = info.devices[i];
    const std::string where = "recording info: device " + std::to_string(i) + " '" + d.name + "'";
    if (d.name.empty() || d.name.size() > kMaxDeviceNameLength ||
        d.name.find_first_of(std::string_view("/ \t\n\0", 5)) != std::string::npos) {
      set_error(error, where + ": a device name is 1.." + std::to_string(kMaxDeviceNameLength) +
                           " characters without '/' or spaces (it becomes the channel rtfuse/hal/<name>)");
      return false;
    }
    if (static_cast<int>(d.kind) > static_cast<int>(kLastDeviceKind)) {
      set_error(error, where + ": unknown device kind " + std::to_string(static_cast<int>(d.kind)));
      return false;
    }
    if (d.stream < 0 || d.stream >= n_streams) {
      set_error(error, where + ": stream " + std::to_string(d.stream) + " does not exist (0.." +
                           std::to_string(n_streams - 1) + ")");
      return false;
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (info.devices[j].name == d.name) {
        set_error(error, where + ": the name is also device " + std::to_string(j) + "'s");
        return false;
      }
      // Video calls travel in their own ring: the log keeps no order between
      // them and another device's bus events, so they cannot share a stream.
      if (info.devices[j].stream == d.stream &&
          (info.devices[j].kind == DeviceKind::kVideo) != (d.kind == DeviceKind::kVideo)) {
        set_error(error, where + ": stream '" + info.streams[static_cast<std::size_t>(d.stream)] +
                             "' has video and non-video devices (device " + std::to_string(j) +
                             " '" + info.devices[j].name + "'); a camera needs a stream of its own");
        return false;
      }
    }
  }
  if (info.files.size() > static_cast<std::size_t>(kMaxRecordedFiles)) {
    set_error(error, "recording info: " + std::to_string(info.files.size()) + " files (at most " +
                         std::to_string(kMaxRecordedFiles) + ")");
    return false;
  }
  for (std::size_t i = 0; i < info.files.size(); ++i) {
    const RecordedFile& f = info.files[i];
    if (!valid_file(f, error)) return false;
    for (std::size_t j = 0; j < i; ++j) {
      if (info.files[j].key == f.key) {
        set_error(error, "recording info: two files for '" + f.key + "'");
        return false;
      }
    }
  }
  return true;
}

std::vector<std::uint8_t> encode_recording_info(const RecordingInfo& info) {
  rtfuse::recording_info_t m;
  m.utime = ns_to_utime(info.start_ns);
  m.format_version = info.format_version;
  m.config_hash = info.config_hash;
  m.num_streams = static_cast<std::int32_t>(info.streams.size());
  m.num_devices = static_cast<std::int32_t>(info.devices.size());
  m.rtfuse_version = info.rtfuse_version;
  m.config_path = info.config_path;
  m.config_text = info.config_text;
  m.streams = info.streams;
  for (const RecordedDevice& d : info.devices) {
    m.device_names.push_back(d.name);
    m.device_kinds.push_back(static_cast<std::int8_t>(d.kind));
    m.device_streams.push_back(static_cast<std::int8_t>(d.stream));
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

bool decode_recording_info(const void* data, int size, RecordingInfo* out, std::string* error) {
  const auto* b = static_cast<const std::uint8_t*>(data);
  // The version sits at a fixed offset (after fingerprint and utime): read it
  // first, so a recording in another format says so instead of "malformed".
  constexpr int kVersionAt = 16;
  if (b != nullptr && size >= kVersionAt + 4 && load_i32(b + kVersionAt) != kHalRecordFormatVersion) {
    set_error(error, "recorded in HAL record format version " + std::to_string(load_i32(b + kVersionAt)) +
                         ", this rtfuse reads version " + std::to_string(kHalRecordFormatVersion) +
                         ": replay it with the rtfuse version that recorded it");
    return false;
  }
  if (b == nullptr || !count_within(b, size, 28, kMaxRecordedStreams) ||
      !count_within(b, size, 32, kMaxRecordedDevices)) {
    set_error(error, "not a recording_info_t: too short, or stream/device counts out of range");
    return false;
  }
  // Then every string: version, config path and text, the stream and device
  // names (counts bounded just above).
  constexpr int kStringsAt = 36;
  if (wire::after_strings(b, size, kStringsAt, 3 + load_i32(b + 28) + load_i32(b + 32), size) < 0) {
    set_error(error,
              "malformed recording_info_t: a string has a NUL inside it, or a length out of range or past the record's " +
                  std::to_string(size) + " bytes");
    return false;
  }
  rtfuse::recording_info_t m;
  if (!decode_message(m, data, size, "recording_info_t", error)) return false;
  RecordingInfo info;
  info.format_version = m.format_version;
  if (!utime_in_range(m.utime)) {
    set_error(error, "recording_info_t: start time " + std::to_string(m.utime) +
                         " us is beyond what nanoseconds can hold: the recording is corrupt");
    return false;
  }
  info.start_ns = utime_to_ns(m.utime);
  info.rtfuse_version = m.rtfuse_version;
  info.config_path = m.config_path;
  info.config_text = m.config_text;
  info.config_hash = m.config_hash;
  info.streams = m.streams;
  for (int i = 0; i < m.num_devices; ++i) {
    const auto idx = static_cast<std::size_t>(i);
    if (m.device_kinds[idx] < 0 || m.device_kinds[idx] > static_cast<std::int8_t>(kLastDeviceKind)) {
      set_error(error, "recording_info_t: device " + std::to_string(i) + " has unknown kind " +
                           std::to_string(m.device_kinds[idx]));
      return false;
    }
    info.devices.push_back(RecordedDevice{m.device_names[idx], static_cast<DeviceKind>(m.device_kinds[idx]),
                                          m.device_streams[idx]});
  }
  if (!validate(info, error)) return false;
  *out = std::move(info);
  return true;
}

std::vector<std::uint8_t> encode_recorded_file(const RecordedFile& file) {
  rtfuse::recording_file_t m;
  m.key = file.key;
  m.path = file.path;
  m.size = static_cast<std::int32_t>(file.text.size());
  m.data.assign(file.text.begin(), file.text.end());
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

bool decode_recorded_file(const void* data, int size, RecordedFile* out, std::string* error) {
  const auto* b = static_cast<const std::uint8_t*>(data);
  // Both strings and the byte count bounded before lcm-gen's decoder sizes
  // anything from them (transport/lcm_wire.hpp).
  int at = 8;
  for (const std::size_t max : {kMaxRecordedFileKeyLength, kMaxRecordedFilePathLength}) {
    const int next = wire::after_string(b, size, at, static_cast<std::int64_t>(max));
    if (next < 0) {
      set_error(error, "malformed recording_file_t: the string at byte " + std::to_string(at) +
                           " has an impossible length or a NUL inside it");
      return false;
    }
    at = next;
  }
  if (b == nullptr || !count_within(b, size, at, static_cast<int>(kMaxRecordedFileBytes))) {
    set_error(error, "malformed recording_file_t: too short, or more than " + std::to_string(kMaxRecordedFileBytes) +
                         " bytes");
    return false;
  }
  rtfuse::recording_file_t m;
  if (!decode_message(m, data, size, "recording_file_t", error)) return false;
  RecordedFile f{m.key, m.path, std::string(m.data.begin(), m.data.end())};
  if (!valid_file(f, error)) return false;
  *out = std::move(f);
  return true;
}

std::vector<std::uint8_t> encode_recording_end(const RecordingEnd& end) {
  rtfuse::recording_end_t m;
  m.utime = ns_to_utime(end.end_ns);
  m.events = end.events;
  m.lost_events = end.lost_events;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

bool decode_recording_end(const void* data, int size, RecordingEnd* out, std::string* error) {
  rtfuse::recording_end_t m;
  if (!decode_message(m, data, size, "recording_end_t", error)) return false;
  if (!utime_in_range(m.utime)) return bad_field(error, "recording_end_t", "utime", m.utime);
  if (m.events < 1) return bad_field(error, "recording_end_t", "event count", m.events);
  if (m.lost_events < 0) return bad_field(error, "recording_end_t", "lost event count", m.lost_events);
  *out = RecordingEnd{utime_to_ns(m.utime), m.events, m.lost_events};
  return true;
}

}  // namespace rtfuse::transport
