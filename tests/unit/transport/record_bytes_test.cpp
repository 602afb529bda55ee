// The bytes of every record kind, pinned: a recording written by an earlier
// build must still load, so a codec change that alters them (a field moved,
// another canonical form, a split of the code) fails here rather than on the
// recordings a robot already holds. A deliberate change of the format bumps
// kHalRecordFormatVersion and these figures together. (The figures are the
// encoders' before the codec was split by record kind, with version 4 in
// the info record since devices' inputs are recorded.)
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "core/xxh64.hpp"
#include "support/hal_record_samples.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::transport {
namespace record_bytes_test {

using test::calibration_file;
using test::camera_info;
using test::dequeue_event;
using test::every_kind;
using test::pattern;
using test::sample_info;

// info, file, end, every bus event kind, a tick, a camera frame and a
// camera call without one, one after the other.
std::vector<std::uint8_t> every_record() {
  std::vector<std::uint8_t> all;
  auto add = [&](const std::uint8_t* b, int n) {
    EXPECT_GT(n, 0);
    if (n > 0) all.insert(all.end(), b, b + n);
  };
  auto add_vector = [&](const std::vector<std::uint8_t>& v) { add(v.data(), static_cast<int>(v.size())); };
  add_vector(encode_recording_info(sample_info()));
  add_vector(encode_recorded_file(calibration_file()));
  add_vector(encode_recording_end({7'000'000'000, 12'345, 6}));

  HalRecordCodec codec(sample_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  for (const hal::BusEvent& ev : every_kind()) add(buf, codec.encode(ev, buf, sizeof buf));
  const std::int64_t consumed[3] = {1, 22, 333};
  add(buf, codec.encode_tick(9'000'000'005, 77, consumed, 3, 5u, buf, sizeof buf));

  HalRecordCodec camera(camera_info().devices);
  const std::vector<std::uint8_t> frame = pattern(300);
  std::vector<std::uint8_t> video(300 + kVideoRecordOverhead);
  add(video.data(), camera.encode_video(dequeue_event(300), frame.data(), video.data(), static_cast<int>(video.size())));
  hal::VideoEvent release;
  release.kind = hal::VideoCallKind::kRelease;
  release.device = 1;
  release.index = 2;
  release.lost_before = 3;
  release.frames_before = 8;
  add(video.data(), camera.encode_video(release, nullptr, video.data(), static_cast<int>(video.size())));
  return all;
}

TEST(HalRecordBytes, EveryRecordKindEncodesAsBefore) {
  const std::vector<std::uint8_t> all = every_record();
  EXPECT_EQ(all.size(), 2352u);
  EXPECT_EQ(xxh64(all.data(), all.size()), 0xa4c22685dd065b06ull) << "the bytes of a record changed";
}

}  // namespace record_bytes_test
}  // namespace rtfuse::transport
