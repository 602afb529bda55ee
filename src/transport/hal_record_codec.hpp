#pragma once
// The records of a HAL recording's calls (the recording itself:
// transport/recording_info.hpp; loading a whole one for a replay:
// runtime/replay/hal_recording.hpp): one hal_can_t / hal_i2c_t / hal_gpio_t /
// hal_clock_t / hal_serial_t per bus call and one hal_video_t per camera
// call (with the frame bytes of a dequeue, transport/hal_video_codec.hpp) on
// rtfuse/hal/<device name>, and one loop_tick_t per loop tick on
// rtfuse/rec/tick.
//
// HalRecordCodec turns a hal::BusEvent into LCM bytes in a caller buffer and
// back (a canonical event round-trips byte for byte). Its message objects
// persist, so encoding allocates only until the largest message was seen once.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"
#include "hal/bus_event.hpp"
#include "hal/video_event.hpp"
#include "transport/hal_video_codec.hpp"
#include "transport/recording_info.hpp"

namespace rtfuse::transport {

constexpr int kMaxTickSensors = 64;
// Largest encoded bus event (a receive of 16 frames on a 48-character device
// name is under 500 bytes).
constexpr int kMaxHalRecordSize = 1024;

struct LoopTick {
  TimeNs time_ns = 0;
  std::int64_t seq = 0;
  std::vector<std::int64_t> consumed;  // per sensor, cumulative up to and including this tick
  std::uint32_t published = 0;         // outputs queued for publishing at this tick
};

class HalRecordCodec {
 public:
  explicit HalRecordCodec(std::vector<RecordedDevice> devices);
  ~HalRecordCodec();
  HalRecordCodec(const HalRecordCodec&) = delete;
  HalRecordCodec& operator=(const HalRecordCodec&) = delete;

  // "rtfuse/hal/<name>", or "" for an index outside the table.
  std::string_view channel(std::uint8_t device) const noexcept;
  // Device index of a rtfuse/hal/* channel, -1 when no device has it.
  int device_of(std::string_view channel) const noexcept;

  // Bytes written into buf, or -1: unknown device, a call kind the device
  // does not record, or capacity too small (kMaxHalRecordSize always fits).
  int encode(const hal::BusEvent& ev, std::uint8_t* buf, int capacity);
  // The event on `channel` back into *out (canonical). False with a reason
  // (wrong type, bad length, impossible value) on anything else.
  bool decode(std::string_view channel, const void* data, int size, hal::BusEvent* out, std::string* error);

  // loop_tick_t; -1 when n is outside 0..kMaxTickSensors or it does not fit.
  int encode_tick(TimeNs time_ns, std::int64_t seq, const std::int64_t* consumed, int n, std::uint32_t published,
                  std::uint8_t* buf,
                  int capacity);
  static bool decode_tick(const void* data, int size, LoopTick* out, std::string* error);

  // hal_video_t of a video device (HalVideoCodec): ev and, when
  // ev.has_frame(), its ev.data_size bytes at data. Bytes written or -1
  // (unknown device, not a video device, capacity too small: data_size +
  // kVideoRecordOverhead fits).
  int encode_video(const hal::VideoEvent& ev, const std::uint8_t* data, std::uint8_t* buf, int capacity);
  // The hal_video_t on `channel` into *out; *frame points at its
  // out->data_size frame bytes (inside this codec, valid until the next
  // decode_video; null without a frame). False with a reason on a wrong
  // type, a bad or truncated length, or an impossible value.
  bool decode_video(std::string_view channel, const void* data, int size, hal::VideoEvent* out,
                    const std::uint8_t** frame, std::string* error);
  // Kind of a device index; false for an index outside the table.
  bool kind_of(int device, DeviceKind* kind) const noexcept;

 private:
  struct Messages;  // the lcm-gen types stay out of this header
  std::vector<RecordedDevice> devices_;
  std::vector<std::string> channels_;
  std::unique_ptr<Messages> msgs_;
  HalVideoCodec video_;
};

}  // namespace rtfuse::transport
