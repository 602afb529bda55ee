#include "transport/hal_record_codec.hpp"

#include <algorithm>
#include <string_view>
#include <utility>

#include "rtfuse/hal_can_t.hpp"
#include "rtfuse/hal_clock_t.hpp"
#include "rtfuse/hal_gpio_t.hpp"
#include "rtfuse/hal_i2c_t.hpp"
#include "rtfuse/hal_serial_t.hpp"
#include "rtfuse/loop_tick_t.hpp"
#include "transport/encode_buffer.hpp"
#include "transport/record_decoding.hpp"

namespace rtfuse::transport {

using hal::BusEvent;
using hal::BusEventKind;
using hal::CanBusState;
using hal::HalStatus;

using decoding::after_device_string;
using decoding::bad_field;
using decoding::count_within;
using decoding::decode_message;
using decoding::set_error;
using decoding::valid_status;

namespace {

constexpr int kMaxBusState = static_cast<int>(CanBusState::kBusOff);

}  // namespace

struct HalRecordCodec::Messages {
  rtfuse::hal_can_t can;
  rtfuse::hal_i2c_t i2c;
  rtfuse::hal_gpio_t gpio;
  rtfuse::hal_clock_t clock;
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
       {&msgs_->can.device, &msgs_->i2c.device, &msgs_->gpio.device, &msgs_->clock.device,
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

int HalRecordCodec::encode_video(const hal::VideoEvent& ev, const std::uint8_t* data, std::uint8_t* buf,
                                 int capacity) {
  if (ev.device >= devices_.size() || devices_[ev.device].kind != DeviceKind::kVideo) return -1;
  return video_.encode(devices_[ev.device].name, ev, data, buf, capacity);
}

bool HalRecordCodec::decode_video(std::string_view channel, const void* data, int size, hal::VideoEvent* out,
                                  const std::uint8_t** frame, std::string* error) {
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
  return video_.decode(static_cast<std::uint8_t>(device), dev.name, data, size, out, frame, error);
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
