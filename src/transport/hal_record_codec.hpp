#pragma once
// HAL-level recordings (rtfused --record) as LCM logs (loading a whole one
// for a replay: runtime/replay/hal_recording.hpp).
//
// A recording is an lcm-logger file whose first event is a recording_info_t
// on rtfuse/rec/info (format version, config, the device table: name, kind
// and producing thread of every recorded bus). Then, in whatever order the
// recorder drained its rings: one hal_can_t / hal_i2c_t / hal_gpio_t /
// hal_clock_t / hal_serial_t per bus call, one hal_video_t per camera call
// (with the frame bytes of a dequeue) on rtfuse/hal/<device name>, one loop_tick_t per
// loop tick on rtfuse/rec/tick, and the published outputs on their own
// channels. Events of one thread (stream) are in call order.
//
// HalRecordCodec turns a hal::BusEvent into LCM bytes in a caller buffer and
// back (a canonical event round-trips byte for byte). Its message objects
// persist, so encoding allocates only until the largest message was seen once.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"
#include "hal/bus_event.hpp"
#include "hal/video_event.hpp"

namespace rtfuse::transport {

// Bump when a rtfuse/hal/* or rtfuse/rec/* record changes meaning or layout.
// 3: a recording ends with its rtfuse/rec/end record.
constexpr std::int32_t kHalRecordFormatVersion = 3;

constexpr std::string_view kRecordingInfoChannel = "rtfuse/rec/info";
constexpr std::string_view kLoopTickChannel = "rtfuse/rec/tick";
constexpr std::string_view kRecordedFileChannel = "rtfuse/rec/file";
constexpr std::string_view kRecordingEndChannel = "rtfuse/rec/end";
constexpr std::string_view kRecordChannelPrefix = "rtfuse/rec/";
constexpr std::string_view kHalChannelPrefix = "rtfuse/hal/";

constexpr int kMaxRecordedDevices = 64;
constexpr int kMaxRecordedStreams = 16;
constexpr std::size_t kMaxDeviceNameLength = 48;
constexpr int kMaxTickSensors = 64;
// Largest encoded bus event (a receive of 16 frames on a 48-character device
// name is under 500 bytes).
constexpr int kMaxHalRecordSize = 1024;
// A hal_video_t is its frame bytes plus at most this much (fields and a
// 48-character device name): size the encode buffer slot_bytes + this.
constexpr int kVideoRecordOverhead = 256;

// Stored as recording_info_t.device_kinds (DEVICE_*): append only.
// kVideo records hal_video_t (hal::VideoEvent), not BusEvents, through its
// own ring, so a video device's stream holds no other device (the order of
// two rings is not kept in the log).
enum class DeviceKind : std::uint8_t { kCan, kI2c, kGpioEdge, kGpioOutput, kClock, kVideo, kSerial };
constexpr DeviceKind kLastDeviceKind = DeviceKind::kSerial;
const char* to_string(DeviceKind k) noexcept;
// The bus call kinds a device of this kind records (none for kVideo).
bool records(DeviceKind device, hal::BusEventKind call) noexcept;

struct RecordedDevice {
  std::string name;  // "can0", "i2c-1", "imu-drdy", "imu-clock"; channel rtfuse/hal/<name>
  DeviceKind kind = DeviceKind::kCan;
  int stream = 0;  // index into RecordingInfo::streams of the thread that uses it
};

// A file the configuration refers to, carried by the recording
// (recording_file_t): the camera's calibration.
struct RecordedFile {
  std::string key;   // the config key naming it: "camera.calibration"
  std::string path;  // where it was read from
  std::string text;  // its bytes
};
constexpr int kMaxRecordedFiles = 8;
constexpr std::size_t kMaxRecordedFileKeyLength = 64;
constexpr std::size_t kMaxRecordedFilePathLength = 4096;
constexpr std::size_t kMaxRecordedFileBytes = 1024 * 1024;

struct RecordingInfo {
  std::int32_t format_version = kHalRecordFormatVersion;
  TimeNs start_ns = 0;
  std::string rtfuse_version;
  std::string config_path;
  std::string config_text;
  std::int64_t config_hash = 0;  // config_text_hash(config_text)
  std::vector<std::string> streams;  // producing threads: "loop", "imu"
  std::vector<RecordedDevice> devices;  // index = hal::BusEvent::device
  // Written as rtfuse/rec/file events after the recording_info_t.
  std::vector<RecordedFile> files;
};

// FNV-1a (64-bit) of the config text.
std::int64_t config_text_hash(std::string_view text) noexcept;

// Device names non-empty, at most kMaxDeviceNameLength, unique, without '/'
// or spaces; stream indices valid; counts within the limits above; a video
// device's stream holds only video devices; files within their limits, keys
// unique.
bool validate(const RecordingInfo& info, std::string* error);

std::vector<std::uint8_t> encode_recording_info(const RecordingInfo& info);
// Fails on bytes that are not a recording_info_t, on another format version
// (named, with the fix), and on an invalid device table.
bool decode_recording_info(const void* data, int size, RecordingInfo* out, std::string* error);

std::vector<std::uint8_t> encode_recorded_file(const RecordedFile& file);
// Fails on bytes that are not a recording_file_t or exceed the limits above.
bool decode_recorded_file(const void* data, int size, RecordedFile* out, std::string* error);

// The recording_end_t a recorder writes last when it closes cleanly.
struct RecordingEnd {
  TimeNs end_ns = 0;             // the last event's time before it
  std::int64_t events = 0;       // events in the log before it
  std::int64_t lost_events = 0;  // events the recorder could not write
};
std::vector<std::uint8_t> encode_recording_end(const RecordingEnd& end);
// Fails on bytes that are not a recording_end_t or hold impossible counts.
bool decode_recording_end(const void* data, int size, RecordingEnd* out, std::string* error);

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

  // hal_video_t of a video device: ev and, when ev.has_frame(), its
  // ev.data_size bytes at data. Bytes written or -1 (unknown device, not a
  // video device, capacity too small: data_size + kVideoRecordOverhead fits).
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
};

}  // namespace rtfuse::transport
