#include "transport/hal_record_codec.hpp"

#include <algorithm>
#include <exception>
#include <limits>
#include <string_view>
#include <utility>

#include "rtfuse/hal_can_t.hpp"
#include "rtfuse/hal_clock_t.hpp"
#include "rtfuse/hal_gpio_t.hpp"
#include "rtfuse/hal_i2c_t.hpp"
#include "rtfuse/hal_serial_t.hpp"
#include "rtfuse/hal_video_t.hpp"
#include "rtfuse/loop_tick_t.hpp"
#include "rtfuse/recording_end_t.hpp"
#include "rtfuse/recording_file_t.hpp"
#include "rtfuse/recording_info_t.hpp"
#include "transport/encode_buffer.hpp"
#include "transport/lcm_wire.hpp"

namespace rtfuse::transport {

using hal::BusEvent;
using hal::BusEventKind;
using hal::CanBusState;
using hal::HalStatus;

using wire::load_i32;
using wire::load_i64;

namespace {

constexpr int kMaxStatus = static_cast<int>(HalStatus::kMalformed);
constexpr int kMaxBusState = static_cast<int>(CanBusState::kBusOff);

void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

// Every hal_* record starts with fingerprint, utime, time_ns, then the device
// string. Offset just past that string, or -1 (wire::after_string).
int after_device_string(const std::uint8_t* b, int size) {
  return wire::after_string(b, size, 8 + 8 + 8, std::numeric_limits<std::int32_t>::max());
}

bool count_within(const std::uint8_t* b, int size, int at, int max) {
  if (at < 0 || size - at < 4) return false;
  const std::int32_t v = load_i32(b + at);
  return v >= 0 && v <= max;
}

template <class Msg>
bool decode_message(Msg& msg, const void* data, int size, const char* type, std::string* error) {
  if (data == nullptr || size < 8) {
    set_error(error, std::string(type) + " record of " + std::to_string(size) + " bytes is too short");
    return false;
  }
  if (load_i64(static_cast<const std::uint8_t*>(data)) != Msg::getHash()) {
    set_error(error, std::string("not a ") + type + " (the type fingerprint differs)");
    return false;
  }
  int used = -1;
  try {
    used = msg.decode(data, 0, size);
  } catch (const std::exception&) {
    used = -1;
  }
  if (used < 0) {
    set_error(error, std::string("malformed ") + type + ": the bytes end early or a length is invalid");
    return false;
  }
  if (used != size) {
    set_error(error, std::string(type) + " has " + std::to_string(size - used) + " trailing bytes");
    return false;
  }
  return true;
}

bool valid_status(int s) { return s >= 0 && s <= kMaxStatus; }

bool bad_field(std::string* error, const char* type, const char* field, long long value) {
  set_error(error, std::string(type) + ": impossible " + field + " " + std::to_string(value));
  return false;
}

}  // namespace

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

// ---------------------------------------------------------------- codec

struct HalRecordCodec::Messages {
  rtfuse::hal_can_t can;
  rtfuse::hal_i2c_t i2c;
  rtfuse::hal_gpio_t gpio;
  rtfuse::hal_clock_t clock;
  rtfuse::hal_video_t video;
  rtfuse::hal_serial_t serial;
  rtfuse::loop_tick_t tick;
};

HalRecordCodec::HalRecordCodec(std::vector<RecordedDevice> devices)
    : devices_(std::move(devices)), msgs_(std::make_unique<Messages>()) {
  for (const RecordedDevice& d : devices_) channels_.push_back(std::string(kHalChannelPrefix) + d.name);
  // Capacity up front, so encoding stops allocating once every name was used.
  msgs_->can.frames.reserve(hal::kBusEventMaxFrames);
  msgs_->i2c.data.reserve(hal::kBusEventMaxBytes);
  msgs_->serial.data.reserve(hal::kBusEventMaxBytes);
  msgs_->tick.consumed.reserve(kMaxTickSensors);
  for (std::string* s :
       {&msgs_->can.device, &msgs_->i2c.device, &msgs_->gpio.device, &msgs_->clock.device, &msgs_->video.device,
        &msgs_->serial.device}) {
    s->reserve(kMaxDeviceNameLength);
  }
}

HalRecordCodec::~HalRecordCodec() = default;

std::string_view HalRecordCodec::channel(std::uint8_t device) const noexcept {
  return device < channels_.size() ? std::string_view(channels_[device]) : std::string_view();
}

int HalRecordCodec::device_of(std::string_view channel) const noexcept {
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    if (channels_[i] == channel) return static_cast<int>(i);
  }
  return -1;
}

int HalRecordCodec::encode(const BusEvent& ev, std::uint8_t* buf, int capacity) {
  if (ev.device >= devices_.size()) return -1;
  const RecordedDevice& dev = devices_[ev.device];
  if (!records(dev.kind, ev.kind)) return -1;
  const std::int64_t utime = ns_to_utime(ev.time_ns);
  const auto status = static_cast<std::int8_t>(ev.status);
  const auto lost = static_cast<std::int32_t>(ev.lost_before);
  switch (dev.kind) {
    case DeviceKind::kCan: {
      rtfuse::hal_can_t& m = msgs_->can;
      m.utime = utime;
      m.time_ns = ev.time_ns;
      m.device = dev.name;
      m.call = ev.kind == BusEventKind::kCanSend ? rtfuse::hal_can_t::SEND : rtfuse::hal_can_t::RECEIVE;
      m.status = status;
      m.bus_state = static_cast<std::int8_t>(ev.bus_state);
      m.max_frames = ev.length;
      m.timeout_ns = ev.timeout_ns;
      m.lost_before = lost;
      const int n = std::min<int>(ev.count, hal::kBusEventMaxFrames);
      m.num_frames = n;
      m.frames.resize(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        const hal::CanFrame& f = ev.frames[i];
        rtfuse::can_frame_t& g = m.frames[static_cast<std::size_t>(i)];
        g.stamp_ns = f.stamp;
        g.id = static_cast<std::int32_t>(f.id);
        g.extended = f.extended;
        g.rtr = f.rtr;
        g.error = f.error;
        g.dlc = static_cast<std::int8_t>(f.dlc);
        std::copy(f.data, f.data + 8, g.data);
      }
      return encode_into(m, buf, capacity);
    }
    case DeviceKind::kI2c: {
      rtfuse::hal_i2c_t& m = msgs_->i2c;
      m.utime = utime;
      m.time_ns = ev.time_ns;
      m.device = dev.name;
      m.call = ev.kind == BusEventKind::kI2cRead ? rtfuse::hal_i2c_t::READ : rtfuse::hal_i2c_t::WRITE;
      m.status = status;
      m.address = ev.address;
      m.reg = ev.reg;
      m.length = ev.length;
      m.value = ev.value;
      m.retries = ev.retries;
      m.lost_before = lost;
      const bool has_data = ev.kind == BusEventKind::kI2cRead && ev.status == HalStatus::kOk && ev.length > 0 &&
                            ev.length <= hal::kBusEventMaxBytes;
      m.num_data = has_data ? ev.length : 0;
      m.data.assign(ev.data, ev.data + m.num_data);
      return encode_into(m, buf, capacity);
    }
    case DeviceKind::kGpioEdge:
    case DeviceKind::kGpioOutput: {
      rtfuse::hal_gpio_t& m = msgs_->gpio;
      const bool wait = ev.kind == BusEventKind::kGpioWaitEdge;
      m.utime = utime;
      m.time_ns = ev.time_ns;
      m.device = dev.name;
      m.call = wait ? rtfuse::hal_gpio_t::WAIT_EDGE : rtfuse::hal_gpio_t::SET;
      m.status = status;
      m.timeout_ns = ev.timeout_ns;
      m.edge_stamp_ns = ev.edge_stamp;
      m.rising = wait && ev.level != 0;
      m.level = !wait && ev.level != 0;
      m.lost_before = lost;
      return encode_into(m, buf, capacity);
    }
    case DeviceKind::kClock: {
      rtfuse::hal_clock_t& m = msgs_->clock;
      m.utime = utime;
      m.time_ns = ev.time_ns;
      m.device = dev.name;
      m.call = ev.kind == BusEventKind::kClockNow ? rtfuse::hal_clock_t::NOW : rtfuse::hal_clock_t::SLEEP_UNTIL;
      m.status = status;
      m.value_ns = ev.clock_ns;
      m.lost_before = lost;
      return encode_into(m, buf, capacity);
    }
    case DeviceKind::kSerial: {
      rtfuse::hal_serial_t& m = msgs_->serial;
      const bool read = ev.kind == BusEventKind::kSerialRead;
      m.utime = utime;
      m.time_ns = ev.time_ns;
      m.device = dev.name;
      m.call = read ? rtfuse::hal_serial_t::READ
                    : (ev.kind == BusEventKind::kSerialWrite ? rtfuse::hal_serial_t::WRITE : rtfuse::hal_serial_t::REOPEN);
      m.status = status;
      m.length = ev.length;
      m.timeout_ns = ev.timeout_ns;
      m.stamp_ns = ev.edge_stamp;
      m.lost_before = lost;
      m.num_data = std::clamp<int>(read ? ev.count : (ev.kind == BusEventKind::kSerialWrite ? ev.length : 0), 0,
                                   hal::kBusEventMaxBytes);
      m.data.assign(ev.data, ev.data + m.num_data);
      return encode_into(m, buf, capacity);
    }
    case DeviceKind::kVideo: return -1;  // records() said no already
  }
  return -1;
}

bool HalRecordCodec::decode(std::string_view channel, const void* data, int size, BusEvent* out,
                            std::string* error) {
  const int device = device_of(channel);
  if (device < 0) {
    set_error(error, "channel " + std::string(channel) + " names no device of the recording_info");
    return false;
  }
  const RecordedDevice& dev = devices_[static_cast<std::size_t>(device)];
  const auto* b = static_cast<const std::uint8_t*>(data);
  const int after_name = b == nullptr ? -1 : after_device_string(b, size);
  BusEvent ev;
  ev.device = static_cast<std::uint8_t>(device);
  auto check_common = [&](const std::string& name, std::int8_t status, const char* type) {
    if (name != dev.name) {
      set_error(error, std::string(type) + " names device '" + name + "' on the channel of '" + dev.name + "'");
      return false;
    }
    if (!valid_status(status)) return bad_field(error, type, "status", status);
    ev.status = static_cast<HalStatus>(status);
    return true;
  };
  switch (dev.kind) {
    case DeviceKind::kCan: {
      constexpr const char* kType = "hal_can_t";
      // call, status, bus_state, max_frames, timeout_ns, lost_before: 19 bytes to num_frames.
      if (!count_within(b, size, after_name < 0 ? -1 : after_name + 19, hal::kBusEventMaxFrames)) {
        set_error(error, "malformed hal_can_t: too short, or more than 16 frames");
        return false;
      }
      rtfuse::hal_can_t& m = msgs_->can;
      if (!decode_message(m, data, size, kType, error) || !check_common(m.device, m.status, kType)) return false;
      if (m.call != rtfuse::hal_can_t::SEND && m.call != rtfuse::hal_can_t::RECEIVE) {
        return bad_field(error, kType, "call", m.call);
      }
      if (m.bus_state < 0 || m.bus_state > kMaxBusState) return bad_field(error, kType, "bus_state", m.bus_state);
      const bool send = m.call == rtfuse::hal_can_t::SEND;
      if (send && m.num_frames != 1) return bad_field(error, kType, "frame count for a send", m.num_frames);
      if (!send && m.num_frames > std::max(m.max_frames, 0)) {
        return bad_field(error, kType, "frame count above max_frames", m.num_frames);
      }
      ev.kind = send ? BusEventKind::kCanSend : BusEventKind::kCanReceive;
      ev.bus_state = static_cast<CanBusState>(m.bus_state);
      ev.length = m.max_frames;
      ev.timeout_ns = m.timeout_ns;
      ev.count = static_cast<std::uint8_t>(m.num_frames);
      for (int i = 0; i < m.num_frames; ++i) {
        const rtfuse::can_frame_t& g = m.frames[static_cast<std::size_t>(i)];
        hal::CanFrame& f = ev.frames[i];
        f.stamp = g.stamp_ns;
        f.id = static_cast<std::uint32_t>(g.id);
        f.extended = g.extended != 0;
        f.rtr = g.rtr != 0;
        f.error = g.error != 0;
        f.dlc = static_cast<std::uint8_t>(g.dlc);
        std::copy(g.data, g.data + 8, f.data);
      }
      ev.time_ns = m.time_ns;
      ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
      break;
    }
    case DeviceKind::kI2c: {
      constexpr const char* kType = "hal_i2c_t";
      // call, status, address, reg, length, value, retries, lost_before: 23 bytes to num_data.
      if (!count_within(b, size, after_name < 0 ? -1 : after_name + 23, hal::kBusEventMaxBytes)) {
        set_error(error, "malformed hal_i2c_t: too short, or more than 64 data bytes");
        return false;
      }
      rtfuse::hal_i2c_t& m = msgs_->i2c;
      if (!decode_message(m, data, size, kType, error) || !check_common(m.device, m.status, kType)) return false;
      if (m.call != rtfuse::hal_i2c_t::READ && m.call != rtfuse::hal_i2c_t::WRITE) {
        return bad_field(error, kType, "call", m.call);
      }
      if (m.address < 0 || m.address > 0xFF) return bad_field(error, kType, "address", m.address);
      if (m.reg < 0 || m.reg > 0xFF) return bad_field(error, kType, "register", m.reg);
      const bool read = m.call == rtfuse::hal_i2c_t::READ;
      if (m.num_data > 0 && (!read || m.num_data != m.length)) {
        return bad_field(error, kType, "data byte count", m.num_data);
      }
      ev.kind = read ? BusEventKind::kI2cRead : BusEventKind::kI2cWrite;
      ev.address = static_cast<std::uint8_t>(m.address);
      ev.reg = static_cast<std::uint8_t>(m.reg);
      ev.length = m.length;
      ev.value = m.value;
      ev.retries = m.retries;
      std::copy(m.data.begin(), m.data.begin() + m.num_data, ev.data);
      ev.time_ns = m.time_ns;
      ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
      break;
    }
    case DeviceKind::kGpioEdge:
    case DeviceKind::kGpioOutput: {
      constexpr const char* kType = "hal_gpio_t";
      if (after_name < 0) {
        set_error(error, "malformed hal_gpio_t: too short or a bad device name length");
        return false;
      }
      rtfuse::hal_gpio_t& m = msgs_->gpio;
      if (!decode_message(m, data, size, kType, error) || !check_common(m.device, m.status, kType)) return false;
      const std::int8_t expected =
          dev.kind == DeviceKind::kGpioEdge ? rtfuse::hal_gpio_t::WAIT_EDGE : rtfuse::hal_gpio_t::SET;
      if (m.call != expected) return bad_field(error, kType, "call for this line", m.call);
      const bool wait = m.call == rtfuse::hal_gpio_t::WAIT_EDGE;
      ev.kind = wait ? BusEventKind::kGpioWaitEdge : BusEventKind::kGpioSet;
      ev.timeout_ns = m.timeout_ns;
      ev.edge_stamp = m.edge_stamp_ns;
      ev.level = (wait ? m.rising : m.level) != 0 ? 1 : 0;
      ev.time_ns = m.time_ns;
      ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
      break;
    }
    case DeviceKind::kClock: {
      constexpr const char* kType = "hal_clock_t";
      if (after_name < 0) {
        set_error(error, "malformed hal_clock_t: too short or a bad device name length");
        return false;
      }
      rtfuse::hal_clock_t& m = msgs_->clock;
      if (!decode_message(m, data, size, kType, error) || !check_common(m.device, m.status, kType)) return false;
      if (m.call != rtfuse::hal_clock_t::NOW && m.call != rtfuse::hal_clock_t::SLEEP_UNTIL) {
        return bad_field(error, kType, "call", m.call);
      }
      ev.kind = m.call == rtfuse::hal_clock_t::NOW ? BusEventKind::kClockNow : BusEventKind::kClockSleepUntil;
      ev.clock_ns = m.value_ns;
      ev.time_ns = m.time_ns;
      ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
      break;
    }
    case DeviceKind::kSerial: {
      constexpr const char* kType = "hal_serial_t";
      // call, status, length, timeout_ns, stamp_ns, lost_before: 26 bytes to num_data.
      if (!count_within(b, size, after_name < 0 ? -1 : after_name + 26, hal::kBusEventMaxBytes)) {
        set_error(error, "malformed hal_serial_t: too short, or more than 64 data bytes");
        return false;
      }
      rtfuse::hal_serial_t& m = msgs_->serial;
      if (!decode_message(m, data, size, kType, error) || !check_common(m.device, m.status, kType)) return false;
      if (m.call != rtfuse::hal_serial_t::READ && m.call != rtfuse::hal_serial_t::WRITE &&
          m.call != rtfuse::hal_serial_t::REOPEN) {
        return bad_field(error, kType, "call", m.call);
      }
      const bool read = m.call == rtfuse::hal_serial_t::READ;
      if (m.call == rtfuse::hal_serial_t::REOPEN && (m.length != 0 || m.num_data != 0)) {
        return bad_field(error, kType, "length of a reopen", m.length != 0 ? m.length : m.num_data);
      }
      if (m.length < 0 || m.length > hal::kBusEventMaxBytes) return bad_field(error, kType, "length", m.length);
      if (read ? m.num_data > m.length : m.num_data != m.length) {
        return bad_field(error, kType, "data byte count", m.num_data);
      }
      // Canonical events only: a stamp belongs to a read that got bytes, a
      // timeout to a read.
      if (m.stamp_ns != 0 && !(read && m.num_data > 0)) return bad_field(error, kType, "stamp_ns", m.stamp_ns);
      if (m.timeout_ns != 0 && !read) return bad_field(error, kType, "timeout_ns of a write", m.timeout_ns);
      ev.kind = read ? BusEventKind::kSerialRead
                     : (m.call == rtfuse::hal_serial_t::WRITE ? BusEventKind::kSerialWrite : BusEventKind::kSerialReopen);
      ev.length = m.length;
      ev.timeout_ns = m.timeout_ns;
      ev.edge_stamp = m.stamp_ns;
      ev.count = read ? static_cast<std::uint8_t>(m.num_data) : 0;
      std::copy(m.data.begin(), m.data.begin() + m.num_data, ev.data);
      ev.time_ns = m.time_ns;
      ev.lost_before = static_cast<std::uint32_t>(m.lost_before);
      break;
    }
    case DeviceKind::kVideo:
      set_error(error, "channel " + std::string(channel) + " is a video device's: its records are hal_video_t");
      return false;
  }
  *out = ev;
  return true;
}

bool HalRecordCodec::kind_of(int device, DeviceKind* kind) const noexcept {
  if (device < 0 || static_cast<std::size_t>(device) >= devices_.size()) return false;
  if (kind != nullptr) *kind = devices_[static_cast<std::size_t>(device)].kind;
  return true;
}

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

int HalRecordCodec::encode_video(const hal::VideoEvent& ev, const std::uint8_t* data, std::uint8_t* buf,
                                 int capacity) {
  if (ev.device >= devices_.size() || devices_[ev.device].kind != DeviceKind::kVideo) return -1;
  const std::int8_t call = video_call(ev.kind);
  if (call < 0) return -1;
  const bool frame = ev.has_frame();
  if (frame && ev.data_size > 0 && data == nullptr) return -1;
  // A frame never fits an int-sized LCM message past 2 GB; nothing real comes close.
  if (ev.data_size > static_cast<std::uint32_t>(std::numeric_limits<std::int32_t>::max() - kVideoRecordOverhead)) {
    return -1;
  }
  rtfuse::hal_video_t& m = msgs_->video;
  m.utime = ns_to_utime(ev.time_ns);
  m.time_ns = ev.time_ns;
  m.device = devices_[ev.device].name;
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

bool HalRecordCodec::decode_video(std::string_view channel, const void* data, int size, hal::VideoEvent* out,
                                  const std::uint8_t** frame, std::string* error) {
  constexpr const char* kType = "hal_video_t";
  if (frame != nullptr) *frame = nullptr;
  const int device = device_of(channel);
  if (device < 0) {
    set_error(error, "channel " + std::string(channel) + " names no device of the recording_info");
    return false;
  }
  const RecordedDevice& dev = devices_[static_cast<std::size_t>(device)];
  if (dev.kind != DeviceKind::kVideo) {
    set_error(error, "channel " + std::string(channel) + " is a " + to_string(dev.kind) +
                         " device's, not a video device's");
    return false;
  }
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
  rtfuse::hal_video_t& m = msgs_->video;
  if (!decode_message(m, data, size, kType, error)) return false;
  if (m.device != dev.name) {
    set_error(error, std::string(kType) + " names device '" + m.device + "' on the channel of '" + dev.name + "'");
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
  ev.device = static_cast<std::uint8_t>(device);
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

int HalRecordCodec::encode_tick(TimeNs time_ns, std::int64_t seq, const std::int64_t* consumed, int n,
                                std::uint32_t published, std::uint8_t* buf, int capacity) {
  if (n < 0 || n > kMaxTickSensors || (n > 0 && consumed == nullptr)) return -1;
  rtfuse::loop_tick_t& m = msgs_->tick;
  m.utime = ns_to_utime(time_ns);
  m.time_ns = time_ns;
  m.seq = seq;
  m.num_sensors = n;
  m.consumed.assign(consumed, consumed + n);
  m.published = static_cast<std::int32_t>(published);
  return encode_into(m, buf, capacity);
}

bool HalRecordCodec::decode_tick(const void* data, int size, LoopTick* out, std::string* error) {
  const auto* b = static_cast<const std::uint8_t*>(data);
  if (b == nullptr || !count_within(b, size, 32, kMaxTickSensors)) {
    set_error(error, "malformed loop_tick_t: too short, or more than " + std::to_string(kMaxTickSensors) +
                         " sensors");
    return false;
  }
  rtfuse::loop_tick_t m;
  if (!decode_message(m, data, size, "loop_tick_t", error)) return false;
  // The loop counts its ticks from 0; a negative count is corrupt, and
  // keeping counts non-negative keeps the loader's gap arithmetic in range.
  if (m.seq < 0) {
    set_error(error, "loop_tick_t: negative tick seq " + std::to_string(m.seq));
    return false;
  }
  out->time_ns = m.time_ns;
  out->seq = m.seq;
  out->consumed = std::move(m.consumed);
  out->published = static_cast<std::uint32_t>(m.published);
  return true;
}

}  // namespace rtfuse::transport
