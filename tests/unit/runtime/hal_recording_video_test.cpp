// load_hal_recording and camera records: frames load into the camera's
// stream, padded to their buffer; a corrupt frame record names its log
// event; frames beyond the memory allowed are refused before they are held.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/replay/hal_recording.hpp"
#include "support/hal_record_samples.hpp"
#include "support/recording_end.hpp"
#include "support/temp_file.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse {
namespace hal_recording_video_test {

using namespace transport;  // NOLINT: the records this loads are transport's
using hal::VideoEvent;
using test::camera_info;
using test::dequeue_event;
using test::pattern;

// A recording of camera_info() whose events after the info are these camera
// records, closed by its end record unless `cut`.
void write_camera_recording(const std::string& path, const std::vector<std::vector<std::uint8_t>>& records,
                            bool cut = false) {
  std::string err;
  EventLogWriter w;
  ASSERT_TRUE(w.open(path, &err)) << err;
  const std::vector<std::uint8_t> info = encode_recording_info(camera_info());
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

TEST(HalVideoLoader, ACorruptFrameRecordNamesTheLogEvent) {
  test::TempFile file("video_corrupt", ".lcm");
  HalRecordCodec codec(camera_info().devices);
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
  HalRecordCodec codec(camera_info().devices);
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
  HalRecordCodec codec(camera_info().devices);
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

}  // namespace hal_recording_video_test
}  // namespace rtfuse
