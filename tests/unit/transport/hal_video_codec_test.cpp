// hal_video_t: the codec round trip of a camera call (the event byte for
// byte, the frame bytes identical) and strict length checks (the loader's
// side: tests/unit/runtime/hal_recording_video_test.cpp).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/hal_record_samples.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::transport {
namespace hal_video_codec_test {

using hal::HalStatus;
using hal::VideoCallKind;
using hal::VideoEvent;
using test::camera_info;
using test::dequeue_event;
using test::pattern;

TEST(HalVideoCodec, AFrameRoundTripsByteForByte) {
  HalRecordCodec codec(camera_info().devices);
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
  HalRecordCodec codec(camera_info().devices);
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
  HalRecordCodec codec(camera_info().devices);
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
  RecordingInfo info = camera_info();
  std::string err;
  EXPECT_TRUE(validate(info, &err)) << err;
  info.devices.push_back({"imu-clock", DeviceKind::kClock, 1});
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("a camera needs a stream of its own"), std::string::npos) << err;
  // The kind survives recording_info_t.
  RecordingInfo back;
  const std::vector<std::uint8_t> bytes = encode_recording_info(camera_info());
  ASSERT_TRUE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err)) << err;
  EXPECT_EQ(back.devices[1].kind, DeviceKind::kVideo);
  EXPECT_STREQ(to_string(DeviceKind::kVideo), "video");
}

}  // namespace hal_video_codec_test
}  // namespace rtfuse::transport
