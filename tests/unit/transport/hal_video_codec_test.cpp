// hal_video_t: the codec round trip of a camera call (the event byte for
// byte, the frame bytes identical), strict length checks, and the loader's
// errors naming the log event of a corrupt or truncated frame record.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/recording_end.hpp"
#include "support/temp_file.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::transport {
namespace {

using hal::HalStatus;
using hal::VideoCallKind;
using hal::VideoEvent;

RecordingInfo make_info() {
  RecordingInfo info;
  info.streams = {"loop", "camera"};
  info.devices = {{"can0", DeviceKind::kCan, 0}, {"cam0", DeviceKind::kVideo, 1}};
  return info;
}

VideoEvent dequeue_event(std::uint32_t n) {
  VideoEvent ev;
  ev.kind = VideoCallKind::kDequeue;
  ev.device = 1;
  ev.time_ns = 5'000'000'123;
  ev.timeout_ns = 100'000'000;
  ev.stamp = 4'999'000'000;
  ev.frames_before = 7;
  ev.sequence = 4'000'000'000u;  // above INT32_MAX: kept unsigned
  ev.bytes_used = n;
  ev.length = n + 16;
  ev.data_size = n;
  ev.index = 2;
  ev.corrupted = 1;
  ev.set_format(hal::VideoFormat{hal::kFourccYuyv, 1344, 376, 2688, 1344u * 376 * 2, 30, 1, 4});
  return ev;
}

std::vector<std::uint8_t> pattern(std::size_t n) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(i * 131 + (i >> 8));
  return v;
}

// A recording of make_info() whose events after the info are these camera
// records, closed by its end record unless `cut`.
void write_camera_recording(const std::string& path, const std::vector<std::vector<std::uint8_t>>& records,
                            bool cut = false) {
  std::string err;
  EventLogWriter w;
  ASSERT_TRUE(w.open(path, &err)) << err;
  const std::vector<std::uint8_t> info = encode_recording_info(make_info());
  ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), info.data(), info.size(), &err));
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto stamp = 2 + static_cast<std::int64_t>(i);
    ASSERT_TRUE(w.write(stamp, "rtfuse/hal/cam0", records[i].data(), records[i].size(), &err)) << err;
  }
  if (!cut) {
    ASSERT_TRUE(test::write_recording_end(w, static_cast<std::int64_t>(records.size()) + 1, &err)) << err;
  }
  ASSERT_TRUE(w.close(&err)) << err;
}

TEST(HalVideoCodec, AFrameRoundTripsByteForByte) {
  HalRecordCodec codec(make_info().devices);
  const std::size_t n = 1344 * 376 * 2;
  const std::vector<std::uint8_t> frame = pattern(n);
  const VideoEvent ev = dequeue_event(static_cast<std::uint32_t>(n));
  std::vector<std::uint8_t> buf(n + kVideoRecordOverhead);
  const int size = codec.encode_video(ev, frame.data(), buf.data(), static_cast<int>(buf.size()));
  ASSERT_GT(size, static_cast<int>(n));
  VideoEvent back;
  const std::uint8_t* bytes = nullptr;
  std::string err;
  ASSERT_TRUE(codec.decode_video("rtfuse/hal/cam0", buf.data(), size, &back, &bytes, &err)) << err;
  EXPECT_TRUE(back == ev);
  ASSERT_NE(bytes, nullptr);
  EXPECT_EQ(std::vector<std::uint8_t>(bytes, bytes + back.data_size), frame);
}

TEST(HalVideoCodec, EveryCallKindRoundTrips) {
  HalRecordCodec codec(make_info().devices);
  for (VideoCallKind k : {VideoCallKind::kRelease, VideoCallKind::kStart, VideoCallKind::kStop,
                          VideoCallKind::kReopen, VideoCallKind::kDequeue}) {
    VideoEvent ev;
    ev.kind = k;
    ev.device = 1;
    ev.status = k == VideoCallKind::kDequeue ? HalStatus::kTimeout : HalStatus::kOk;
    ev.timeout_ns = k == VideoCallKind::kDequeue ? 33'000'000 : 0;
    ev.index = k == VideoCallKind::kRelease ? 3 : -1;
    ev.lost_before = 2;
    ev.frames_before = 9;
    std::uint8_t buf[kVideoRecordOverhead];
    const int size = codec.encode_video(ev, nullptr, buf, static_cast<int>(sizeof buf));
    ASSERT_GT(size, 0) << to_string(k);
    VideoEvent back;
    std::string err;
    ASSERT_TRUE(codec.decode_video("rtfuse/hal/cam0", buf, size, &back, nullptr, &err)) << err;
    EXPECT_TRUE(back == ev) << to_string(k);
  }
}

TEST(HalVideoCodec, WrongDeviceAndBadLengthsAreErrors) {
  HalRecordCodec codec(make_info().devices);
  VideoEvent ev = dequeue_event(64);
  const std::vector<std::uint8_t> frame = pattern(64);
  std::uint8_t small[64];
  EXPECT_EQ(codec.encode_video(ev, frame.data(), small, sizeof small), -1);  // does not fit
  std::vector<std::uint8_t> buf(64 + kVideoRecordOverhead);
  const int size = codec.encode_video(ev, frame.data(), buf.data(), static_cast<int>(buf.size()));
  ASSERT_GT(size, 0);
  VideoEvent bus_on_video = ev;
  bus_on_video.device = 0;  // the CAN bus is no video device
  EXPECT_EQ(codec.encode_video(bus_on_video, frame.data(), buf.data(), static_cast<int>(buf.size())), -1);

  VideoEvent back;
  std::string err;
  EXPECT_FALSE(codec.decode_video("rtfuse/hal/can0", buf.data(), size, &back, nullptr, &err));
  EXPECT_NE(err.find("not a video device"), std::string::npos) << err;
  hal::BusEvent bus;
  EXPECT_FALSE(codec.decode("rtfuse/hal/cam0", buf.data(), size, &bus, &err));
  EXPECT_NE(err.find("hal_video_t"), std::string::npos) << err;
  // Truncated anywhere: never a crash, always an error.
  for (int cut = 0; cut < size; cut += (cut < 200 ? 1 : 7)) {
    EXPECT_FALSE(codec.decode_video("rtfuse/hal/cam0", buf.data(), cut, &back, nullptr, &err)) << cut;
  }
  // A frame length that claims more than the record holds.
  std::vector<std::uint8_t> bad(buf.begin(), buf.begin() + size);
  const std::size_t at = static_cast<std::size_t>(size) - 64 - 4;  // num_data, then 64 bytes
  bad[at] = 0x7F;
  EXPECT_FALSE(codec.decode_video("rtfuse/hal/cam0", bad.data(), size, &back, nullptr, &err));
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
}

TEST(HalVideoCodec, AVideoDeviceNeedsAStreamOfItsOwn) {
  RecordingInfo info = make_info();
  std::string err;
  EXPECT_TRUE(validate(info, &err)) << err;
  info.devices.push_back({"imu-clock", DeviceKind::kClock, 1});
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("a camera needs a stream of its own"), std::string::npos) << err;
  // The kind survives recording_info_t.
  RecordingInfo back;
  const std::vector<std::uint8_t> bytes = encode_recording_info(make_info());
  ASSERT_TRUE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err)) << err;
  EXPECT_EQ(back.devices[1].kind, DeviceKind::kVideo);
  EXPECT_STREQ(to_string(DeviceKind::kVideo), "video");
}

TEST(HalVideoLoader, ACorruptFrameRecordNamesTheLogEvent) {
  test::TempFile file("video_corrupt", ".lcm");
  HalRecordCodec codec(make_info().devices);
  const std::vector<std::uint8_t> frame = pattern(256);
  std::vector<std::uint8_t> buf(256 + kVideoRecordOverhead);
  const int size = codec.encode_video(dequeue_event(256), frame.data(), buf.data(), static_cast<int>(buf.size()));
  ASSERT_GT(size, 0);
  // The same record cut short, as a complete log event.
  const auto whole = buf.begin() + size;
  write_camera_recording(file.path(), {{buf.begin(), whole}, {buf.begin(), whole - 100}}, true);
  std::string err;
  EventLogReader reader;
  ASSERT_TRUE(reader.open(file.path(), &err)) << err;
  HalRecording rec;
  EXPECT_FALSE(load_hal_recording(reader, HalRecordingOptions{}, &rec, &err));
  EXPECT_NE(err.find("event 2 on channel rtfuse/hal/cam0 cannot be decoded: malformed hal_video_t"),
            std::string::npos)
      << err;
}

TEST(HalVideoLoader, FramesLoadIntoTheCameraStream) {
  test::TempFile file("video_load", ".lcm");
  HalRecordCodec codec(make_info().devices);
  const std::vector<std::uint8_t> frame = pattern(300);
  std::vector<std::uint8_t> buf(300 + kVideoRecordOverhead);
  VideoEvent ev = dequeue_event(300);
  const int size = codec.encode_video(ev, frame.data(), buf.data(), static_cast<int>(buf.size()));
  write_camera_recording(file.path(), {{buf.begin(), buf.begin() + size}});
  std::string err;
  EventLogReader reader;
  ASSERT_TRUE(reader.open(file.path(), &err)) << err;
  HalRecording rec;
  ASSERT_TRUE(load_hal_recording(reader, HalRecordingOptions{}, &rec, &err)) << err;
  ASSERT_EQ(rec.videos.size(), 2u);
  ASSERT_EQ(rec.videos[1]->size(), 1u);
  EXPECT_TRUE(rec.videos[1]->event(0) == ev);
  EXPECT_EQ(rec.videos[1]->log_event(0), 1);
  // Kept zero-padded to the buffer's length (316), the frame bytes first.
  const std::uint8_t* data = rec.videos[1]->data(0);
  EXPECT_EQ(std::vector<std::uint8_t>(data, data + 300), frame);
  EXPECT_EQ(data[315], 0);
}

TEST(HalVideoLoader, FramesBeyondTheMemoryAllowedAreRefusedBeforeTheyAreHeld) {
  // The fuzzer's out-of-memory: each frame record of a few bytes claiming a
  // 4 GiB buffer, padded in memory to it. The loader counts what the frames
  // will take and stops at the limit with the figure.
  test::TempFile file("video_memory", ".lcm");
  HalRecordCodec codec(make_info().devices);
  const std::vector<std::uint8_t> frame = pattern(64);
  std::vector<std::uint8_t> buf(64 + kVideoRecordOverhead);
  VideoEvent ev = dequeue_event(64);
  ev.length = 3u << 20;  // a 3 MiB buffer holding 64 bytes, as an MJPEG frame may
  const int size = codec.encode_video(ev, frame.data(), buf.data(), static_cast<int>(buf.size()));
  ASSERT_GT(size, 0);
  const std::vector<std::uint8_t> record(buf.begin(), buf.begin() + size);
  write_camera_recording(file.path(), {record, record, record});
  std::string err;
  HalRecordingOptions options;
  options.max_frame_bytes = 8u << 20;  // two frames fit, the third does not
  EventLogReader reader;
  ASSERT_TRUE(reader.open(file.path(), &err)) << err;
  HalRecording rec;
  EXPECT_FALSE(load_hal_recording(reader, options, &rec, &err));
  EXPECT_NE(err.find("event 3 on channel rtfuse/hal/cam0: the camera frames up to here need 9 MiB in memory (this one "
                     "a buffer of 3145728 bytes), more than the 8 MiB allowed"),
            std::string::npos)
      << err;
  options.max_frame_bytes = 9u << 20;
  ASSERT_TRUE(reader.open(file.path(), &err)) << err;
  HalRecording enough;
  EXPECT_TRUE(load_hal_recording(reader, options, &enough, &err)) << err;
}

}  // namespace
}  // namespace rtfuse::transport
