// RecordingVideoStream around a MockVideoStream: one record per call, the
// frame bytes exactly as lent, loss counting with lost_before and the frame
// numbers, and no allocation on the recording path.
#include "hal/recording_video_stream.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "hal/mock/mock_video_stream.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::hal {
namespace recording_video_stream_test {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 10 * kMs;
constexpr TimeNs kFirst = 1'000 * kMs;

// Frames every kPeriod from kFirst; byte i of frame s is s * 7 + i.
class PatternSource final : public mock::FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kFirst + taken_ * kPeriod; }
  std::uint32_t fill(TimeNs, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    ++taken_;
    for (std::uint32_t i = 0; data != nullptr && i < capacity; ++i) {
      data[i] = static_cast<std::uint8_t>(sequence * 7 + i);
    }
    return capacity;
  }

 private:
  int taken_ = 0;
};

struct Rig {
  explicit Rig(std::size_t frame_slots = 8, std::size_t events = 32)
      : ring(mock.format().image_size, frame_slots, events) {}
  mock::SimClock clock{kFirst - 5 * kMs};
  PatternSource source;
  mock::MockVideoStream mock{clock, source, mock::yuyv_format(16, 4, 100, 3)};
  VideoRecordRing ring;
  RecordingVideoStream rec{mock, ring, 3, &clock};

  // Pops the oldest record; its frame bytes into *bytes.
  VideoEvent pop(std::vector<std::uint8_t>* bytes = nullptr) {
    const std::uint8_t* frame = nullptr;
    const VideoEvent* ev = ring.peek(&frame);
    EXPECT_NE(ev, nullptr);
    if (ev == nullptr) return VideoEvent{};
    const VideoEvent out = *ev;
    if (bytes != nullptr) bytes->assign(frame, frame + (frame != nullptr ? out.data_size : 0));
    ring.pop();
    return out;
  }
};

TEST(HalRecordingVideoStream, RecordsEveryCallAndTheFrameBytes) {
  Rig r;
  ASSERT_EQ(r.rec.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(r.rec.dequeue(100 * kMs, &f), HalStatus::kOk);
  const std::vector<std::uint8_t> lent(f.data, f.data + f.bytes_used);
  ASSERT_EQ(r.rec.release(f.index), HalStatus::kOk);
  r.rec.stop();
  const HalStatus after_stop = r.rec.dequeue(5 * kMs, &f);  // not streaming: an error
  EXPECT_NE(after_stop, HalStatus::kOk);
  EXPECT_EQ(r.ring.events(), 5u);
  EXPECT_EQ(r.ring.frames(), 1u);

  const VideoEvent start = r.pop();
  EXPECT_EQ(start.kind, VideoCallKind::kStart);
  EXPECT_EQ(start.device, 3);
  EXPECT_EQ(start.status, HalStatus::kOk);
  EXPECT_EQ(start.index, -1);
  EXPECT_EQ(start.width, 16);
  EXPECT_EQ(start.image_size, 16u * 4 * 2);
  EXPECT_EQ(start.time_ns, kFirst - 5 * kMs);

  std::vector<std::uint8_t> bytes;
  const VideoEvent dq = r.pop(&bytes);
  EXPECT_EQ(dq.kind, VideoCallKind::kDequeue);
  EXPECT_EQ(dq.timeout_ns, 100 * kMs);
  EXPECT_TRUE(dq.has_frame());
  EXPECT_EQ(dq.index, f.index);
  EXPECT_EQ(dq.stamp, kFirst);
  EXPECT_EQ(dq.sequence, 0u);
  EXPECT_EQ(dq.bytes_used, 128u);
  EXPECT_EQ(dq.length, 128u);
  EXPECT_EQ(dq.data_size, 128u);
  EXPECT_EQ(dq.corrupted, 0);
  EXPECT_EQ(dq.frames_before, 0);
  EXPECT_EQ(bytes, lent);

  const VideoEvent rel = r.pop();
  EXPECT_EQ(rel.kind, VideoCallKind::kRelease);
  EXPECT_EQ(rel.index, dq.index);
  EXPECT_EQ(rel.frames_before, 1);
  EXPECT_EQ(r.pop().kind, VideoCallKind::kStop);
  const VideoEvent closed = r.pop();
  EXPECT_EQ(closed.kind, VideoCallKind::kDequeue);
  EXPECT_EQ(closed.status, after_stop);
  EXPECT_FALSE(closed.has_frame());
  EXPECT_EQ(closed.data_size, 0u);
  EXPECT_EQ(r.ring.events(), 0u);
  EXPECT_EQ(r.ring.frames(), 0u);
  EXPECT_EQ(r.rec.frames_recorded(), 1);
  EXPECT_EQ(r.rec.overflows(), 0);
}

TEST(HalRecordingVideoStream, RecordsFaultsAsTheDriverSawThem) {
  Rig r;
  ASSERT_EQ(r.rec.start(), HalStatus::kOk);
  r.mock.corrupt_next();
  r.mock.set_next_bytes_used(100);
  VideoFrame f;
  ASSERT_EQ(r.rec.dequeue(100 * kMs, &f), HalStatus::kOk);
  r.rec.release(f.index);
  r.mock.unplug();
  EXPECT_EQ(r.rec.dequeue(100 * kMs, &f), HalStatus::kClosed);
  r.mock.refuse_reopens(1);
  EXPECT_NE(r.rec.reopen(), HalStatus::kOk);
  EXPECT_EQ(r.rec.reopen(), HalStatus::kOk);

  r.pop();
  std::vector<std::uint8_t> bytes;
  const VideoEvent dq = r.pop(&bytes);
  EXPECT_EQ(dq.corrupted, 1);
  EXPECT_EQ(dq.bytes_used, 100u);
  EXPECT_EQ(dq.data_size, 100u);  // the buffer as used, not the whole capacity
  EXPECT_EQ(bytes.size(), 100u);
  r.pop();
  EXPECT_EQ(r.pop().status, HalStatus::kClosed);
  const VideoEvent refused = r.pop();
  EXPECT_EQ(refused.kind, VideoCallKind::kReopen);
  EXPECT_NE(refused.status, HalStatus::kOk);
  EXPECT_EQ(r.pop().status, HalStatus::kOk);
}

TEST(HalRecordingVideoStream, AFullRingDropsCountsAndTheNextRecordSaysSo) {
  Rig r(/*frame_slots=*/2, /*events=*/64);
  ASSERT_EQ(r.rec.start(), HalStatus::kOk);
  // Nobody drains: frames 0 and 1 fit, 2..4 are lost (their releases still fit).
  for (int i = 0; i < 5; ++i) {
    VideoFrame f;
    ASSERT_EQ(r.rec.dequeue(100 * kMs, &f), HalStatus::kOk);
    ASSERT_EQ(r.rec.release(f.index), HalStatus::kOk);
  }
  EXPECT_EQ(r.rec.overflows(), 3);
  EXPECT_EQ(r.rec.frames_lost(), 3);
  EXPECT_EQ(r.rec.frames_recorded(), 2);
  // start, dq0, rel0, dq1, rel1, then rel2 (1 lost before), rel3 (1), rel4 (1).
  ASSERT_EQ(r.ring.events(), 8u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(r.pop().lost_before, 0u);
  const VideoEvent rel2 = r.pop();
  EXPECT_EQ(rel2.kind, VideoCallKind::kRelease);
  EXPECT_EQ(rel2.lost_before, 1u);
  EXPECT_EQ(rel2.frames_before, 3);  // frame 2 was lent, and not recorded
  EXPECT_EQ(r.pop().lost_before, 1u);
  EXPECT_EQ(r.pop().lost_before, 1u);

  // Drained: recording resumes, the next record is clean.
  VideoFrame f;
  ASSERT_EQ(r.rec.dequeue(100 * kMs, &f), HalStatus::kOk);
  std::vector<std::uint8_t> bytes;
  const VideoEvent dq = r.pop(&bytes);
  EXPECT_EQ(dq.lost_before, 0u);
  EXPECT_EQ(dq.frames_before, 5);
  EXPECT_EQ(bytes[0], static_cast<std::uint8_t>(5 * 7));
}

TEST(HalRecordingVideoStream, AFrameLargerThanTheSlotIsClipped) {
  mock::SimClock clock(kFirst);
  PatternSource source;
  mock::MockVideoStream mock(clock, source, mock::yuyv_format(16, 4, 100, 3));
  VideoRecordRing ring(64, 2, 8);
  RecordingVideoStream rec(mock, ring, 0);
  ASSERT_EQ(rec.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(rec.dequeue(100 * kMs, &f), HalStatus::kOk);
  ring.pop();  // start
  const std::uint8_t* frame = nullptr;
  const VideoEvent* ev = ring.peek(&frame);
  ASSERT_NE(ev, nullptr);
  EXPECT_EQ(ev->bytes_used, 128u);
  EXPECT_EQ(ev->data_size, 64u);
  EXPECT_EQ(ev->time_ns, 0);  // no clock
  EXPECT_EQ(std::memcmp(frame, f.data, 64), 0);
}

TEST(HalRecordingVideoStream, RecordingCallsDoNotAllocate) {
  Rig r(/*frame_slots=*/2, /*events=*/6);
  ASSERT_EQ(r.rec.start(), HalStatus::kOk);
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 20; ++i) {
    VideoFrame f;
    if (r.rec.dequeue(100 * kMs, &f) == HalStatus::kOk) r.rec.release(f.index);
    if (i % 4 == 0) {
      while (r.ring.peek(nullptr) != nullptr) r.ring.pop();
    }
  }
  r.rec.stop();
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(r.rec.overflows(), 0);
  EXPECT_GT(r.rec.frames_recorded(), 0);
}

}  // namespace recording_video_stream_test
}  // namespace rtfuse::hal
