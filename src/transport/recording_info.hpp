#pragma once
// What a HAL recording (rtfused --record, rtfuse-sim) is, and its records
// about itself rather than about a bus call.
//
// A recording is an lcm-logger file whose first event is a recording_info_t
// on rtfuse/rec/info (format version, config, the device table: name, kind
// and producing thread of every recorded bus), then a recording_file_t on
// rtfuse/rec/file for each file the config names that a replay needs. Then,
// in whatever order the recorder drained its rings, the bus calls, camera
// calls and loop ticks (transport/hal_record_codec.hpp) and the published
// outputs on their own channels; events of one thread (stream) are in call
// order. A recorder that stops writes a recording_end_t on rtfuse/rec/end
// last.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"
#include "hal/bus_event.hpp"

namespace rtfuse::transport {

// Bump when a rtfuse/hal/* or rtfuse/rec/* record changes meaning or layout.
// 3: a recording ends with its rtfuse/rec/end record.
// 4: devices' LCM inputs (the navigator's goals) on rtfuse/rec/in/<channel>,
//    and how many of each the loop had taken after the sensors in a tick.
constexpr std::int32_t kHalRecordFormatVersion = 4;

constexpr std::string_view kRecordingInfoChannel = "rtfuse/rec/info";
constexpr std::string_view kLoopTickChannel = "rtfuse/rec/tick";
constexpr std::string_view kRecordedFileChannel = "rtfuse/rec/file";
constexpr std::string_view kRecordingEndChannel = "rtfuse/rec/end";
constexpr std::string_view kRecordChannelPrefix = "rtfuse/rec/";
constexpr std::string_view kRecordedInputPrefix = "rtfuse/rec/in/";
constexpr std::string_view kHalChannelPrefix = "rtfuse/hal/";

constexpr int kMaxRecordedDevices = 64;
constexpr int kMaxRecordedStreams = 16;
constexpr std::size_t kMaxDeviceNameLength = 48;

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

}  // namespace rtfuse::transport
