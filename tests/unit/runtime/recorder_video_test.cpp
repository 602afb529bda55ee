// Recorder video rings: a camera recorded through RecordingVideoStream is
// written as hal_video_t records and loads back with identical frames; a
// full ring is counted as lost frames and ends the camera's stream there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "hal/mock/mock_can_bus.hpp"
#include "hal/mock/mock_video_stream.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/recording_can_bus.hpp"
#include "hal/recording_video_stream.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "runtime/pipeline/recorder.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "support/temp_file.hpp"

namespace rtfuse::runtime {
namespace recorder_video_test {

using hal::HalStatus;
using hal::VideoFrame;
using transport::DeviceKind;
using transport::RecordingInfo;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kFirst = 1'000 * kMs;

class Source final : public hal::mock::FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kFirst + taken_ * 33 * kMs; }
  std::uint32_t fill(TimeNs, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    ++taken_;
    for (std::uint32_t i = 0; data != nullptr && i < capacity; ++i) {
      data[i] = static_cast<std::uint8_t>((i * 31) ^ (i >> 9) ^ sequence);
    }
    return capacity;
  }

 private:
  int taken_ = 0;
};

RecordingInfo make_info() {
  RecordingInfo info;
  info.rtfuse_version = "0.1.0";
  info.config_text = "[camera]\n";
  info.streams = {"loop", "camera"};
  info.devices = {{"can0", DeviceKind::kCan, 0}, {"cam0", DeviceKind::kVideo, 1}};
  return info;
}

bool load(const std::string& path, HalRecording* rec, std::string* err) {
  transport::EventLogReader reader;
  if (!reader.open(path, err)) return false;
  return load_hal_recording(reader, HalRecordingOptions{}, rec, err);
}

struct LiveFrame {
  hal::VideoFrame frame;
  std::vector<std::uint8_t> bytes;
};

TEST(RecorderVideo, FramesRoundTripThroughTheFileByteForByte) {
  test::TempFile file("rec_video", ".lcm");
  std::string err;
  auto rec = Recorder::create(file.path(), make_info(), RecorderRingSizes{}, &err);
  ASSERT_NE(rec, nullptr) << err;
  hal::mock::SimClock clock(kFirst - kMs);
  Source source;
  // VGA side-by-side YUYV: 1344 * 376 * 2 = 1 MB a frame.
  hal::mock::MockVideoStream camera(clock, source, hal::mock::yuyv_format(1344, 376, 30, 4));
  ASSERT_EQ(camera.format().image_size, 1344u * 376 * 2);
  hal::VideoRecordRing* ring = rec->add_video_ring(1, camera.format().image_size, 8, 0, &err);
  ASSERT_NE(ring, nullptr) << err;
  hal::RecordingVideoStream recorded(camera, *ring, 1, &clock);
  // The bus rings are untouched: a CAN event on the loop stream still records.
  hal::mock::MockCanBus can;
  hal::RecordingCanBus can_rec(can, rec->ring(0), 0, &clock);
  ASSERT_TRUE(rec->start(&err)) << err;

  std::vector<LiveFrame> live;
  ASSERT_EQ(recorded.start(), HalStatus::kOk);
  for (int i = 0; i < 6; ++i) {
    LiveFrame f;
    ASSERT_EQ(recorded.dequeue(100 * kMs, &f.frame), HalStatus::kOk);
    f.bytes.assign(f.frame.data, f.frame.data + f.frame.bytes_used);
    ASSERT_EQ(recorded.release(f.frame.index), HalStatus::kOk);
    live.push_back(std::move(f));
    hal::CanFrame cf[4];
    HalStatus st = HalStatus::kOk;
    can_rec.receive(cf, 4, 0, &st);
    while (rec->backlogged()) usleep(1000);  // lockstep: nothing lost in this test
  }
  recorded.stop();
  ASSERT_TRUE(rec->stop(&err)) << err;
  const RecorderStats stats = rec->stats();
  EXPECT_EQ(stats.video_frames_written, 6);
  EXPECT_EQ(stats.video_frames_lost, 0);
  EXPECT_EQ(stats.encode_errors, 0);
  EXPECT_EQ(stats.bus_events_lost[1], 0);

  HalRecording loaded;
  ASSERT_TRUE(load(file.path(), &loaded, &err)) << err;
  ASSERT_EQ(loaded.videos.size(), 2u);
  EXPECT_EQ(loaded.videos[0]->size(), 0u);
  EXPECT_EQ(loaded.streams[0]->size(), 6u);  // the CAN receives
  const hal::replay::ReplayVideoLog& log = *loaded.videos[1];
  ASSERT_EQ(log.size(), 1u + 6 * 2 + 1);
  EXPECT_EQ(log.frames(), 6);
  EXPECT_EQ(loaded.lost_frames, 0);

  // Replayed: the same calls give the same frames, every byte.
  hal::replay::ReplayVideoLog& replay_log = *loaded.videos[1];
  hal::replay::ReplayVideoStream replay(replay_log, 1);
  EXPECT_EQ(replay.format().width, 1344);
  EXPECT_EQ(replay.format().image_size, camera.format().image_size);
  ASSERT_EQ(replay.start(), HalStatus::kOk);
  for (const LiveFrame& f : live) {
    VideoFrame g;
    ASSERT_EQ(replay.dequeue(100 * kMs, &g), HalStatus::kOk) << replay.last_error();
    EXPECT_EQ(g.index, f.frame.index);
    EXPECT_EQ(g.stamp, f.frame.stamp);
    EXPECT_EQ(g.sequence, f.frame.sequence);
    EXPECT_EQ(g.bytes_used, f.frame.bytes_used);
    EXPECT_EQ(g.length, f.frame.length);
    EXPECT_EQ(g.corrupted, f.frame.corrupted);
    ASSERT_EQ(std::vector<std::uint8_t>(g.data, g.data + g.bytes_used), f.bytes);
    ASSERT_EQ(replay.release(g.index), HalStatus::kOk);
  }
  replay.stop();
  EXPECT_TRUE(replay_log.at_end());
  EXPECT_FALSE(replay_log.diverged());
}

TEST(RecorderVideo, AFullRingLosesFramesAndTheLoadSaysWhich) {
  test::TempFile file("rec_video_lost", ".lcm");
  std::string err;
  auto rec = Recorder::create(file.path(), make_info(), RecorderRingSizes{}, &err);
  ASSERT_NE(rec, nullptr) << err;
  hal::mock::SimClock clock(kFirst - kMs);
  Source source;
  hal::mock::MockVideoStream camera(clock, source, hal::mock::yuyv_format(32, 8, 30, 4));
  // The writer is not started: two frame slots, then the ring is full.
  hal::VideoRecordRing* ring = rec->add_video_ring(1, camera.format().image_size, 2, 0, &err);
  ASSERT_NE(ring, nullptr) << err;
  EXPECT_EQ(rec->add_video_ring(1, 64, 2, 0, &err), nullptr);  // one ring per stream
  EXPECT_EQ(rec->add_video_ring(0, 64, 2, 0, &err), nullptr);  // no camera on "loop"
  EXPECT_NE(err.find("no video device"), std::string::npos) << err;
  hal::RecordingVideoStream recorded(camera, *ring, 1, &clock);
  ASSERT_EQ(recorded.start(), HalStatus::kOk);
  for (int i = 0; i < 4; ++i) {
    VideoFrame f;
    ASSERT_EQ(recorded.dequeue(100 * kMs, &f), HalStatus::kOk);
    recorded.release(f.index);
  }
  EXPECT_EQ(recorded.frames_lost(), 2);
  ASSERT_TRUE(rec->stop(&err)) << err;  // never started: stop() drains what is queued
  const RecorderStats stats = rec->stats();
  EXPECT_EQ(stats.video_frames_written, 2);
  EXPECT_EQ(stats.video_frames_lost, 2);
  EXPECT_EQ(stats.bus_events_lost[1], 2);

  HalRecording loaded;
  ASSERT_TRUE(load(file.path(), &loaded, &err)) << err;
  EXPECT_EQ(loaded.lost_frames, 1);  // the stream ends at the first hole: frame 2
  EXPECT_EQ(loaded.videos[1]->first_lost_frame(), 2);
  ASSERT_FALSE(loaded.warnings.empty());
  EXPECT_NE(loaded.warnings[0].find("stream 'camera': the recorder lost 1 calls (frames 2..2)"), std::string::npos)
      << loaded.warnings[0];
}

}  // namespace recorder_video_test
}  // namespace rtfuse::runtime
