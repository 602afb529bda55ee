// MockVideoStream on a SimClock: frames at the source's times, a V4L2-like
// buffer queue (lost frames consume sequence numbers), and fault injection.
#include "hal/mock/mock_video_stream.hpp"

#include <gtest/gtest.h>

#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::hal::mock {
namespace mock_video_stream_test {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 10 * kMs;  // 100 fps
constexpr TimeNs kFirst = 1'000 * kMs;

// Frames every kPeriod from kFirst; paints each frame's low sequence byte.
class PatternSource final : public FrameGenerator {
 public:
  explicit PatternSource(int count = 1'000'000) : count_(count) {}
  TimeNs next_frame_time() noexcept override { return taken_ < count_ ? kFirst + taken_ * kPeriod : -1; }
  std::uint32_t fill(TimeNs stamp, std::uint32_t sequence, std::uint8_t* data,
                     std::uint32_t capacity) noexcept override {
    last_stamp = stamp;
    last_sequence = sequence;
    ++taken_;
    if (data == nullptr) {
      ++skipped;
      return 0;
    }
    for (std::uint32_t i = 0; i < capacity; ++i) data[i] = static_cast<std::uint8_t>(sequence);
    ++painted;
    return bytes_used != 0 ? bytes_used : capacity;
  }
  std::uint32_t bytes_used = 0;  // 0: the whole buffer
  int painted = 0;
  int skipped = 0;
  TimeNs last_stamp = -1;
  std::uint32_t last_sequence = 0;

 private:
  int count_;
  int taken_ = 0;
};

class MockVideoStreamTest : public ::testing::Test {
 protected:
  MockVideoStreamTest() : clock_(kFirst - 5 * kMs), stream_(clock_, source_, yuyv_format(8, 2, 100, 3)) {}
  SimClock clock_;
  PatternSource source_;
  MockVideoStream stream_;
};

TEST(MockVideoFormat, YuyvHelperFillsTheNegotiatedFormat) {
  const VideoFormat f = yuyv_format(2560, 720, 30, 4);
  EXPECT_EQ(f.pixel_format, kFourccYuyv);
  EXPECT_EQ(f.width, 2560);
  EXPECT_EQ(f.height, 720);
  EXPECT_EQ(f.bytes_per_line, 5120);
  EXPECT_EQ(f.image_size, 2u * 2560 * 720);
  EXPECT_EQ(f.fps_numerator, 30u);
  EXPECT_EQ(f.fps_denominator, 1u);
  EXPECT_EQ(f.buffers, 4);
}

TEST(MockVideoFormat, BufferCountIsClampedToTheFixedCapacity) {
  SimClock clock;
  PatternSource source;
  MockVideoStream s(clock, source, yuyv_format(4, 4, 30, 20));
  EXPECT_EQ(s.format().buffers, kMaxVideoBuffers);
}

TEST_F(MockVideoStreamTest, DequeueJumpsTheSimClockToEachFrame) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  for (std::uint32_t n = 0; n < 5; ++n) {
    VideoFrame f;
    ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk) << stream_.last_error();
    EXPECT_EQ(f.stamp, kFirst + static_cast<TimeNs>(n) * kPeriod);
    EXPECT_EQ(clock_.now(), f.stamp);
    EXPECT_EQ(f.sequence, n);
    EXPECT_EQ(f.bytes_used, 32u);
    EXPECT_EQ(f.length, 32u);
    EXPECT_EQ(f.data[0], static_cast<std::uint8_t>(n));
    EXPECT_EQ(f.data[31], static_cast<std::uint8_t>(n));
    EXPECT_FALSE(f.corrupted);
    ASSERT_EQ(stream_.release(f.index), HalStatus::kOk);
  }
  EXPECT_EQ(stream_.stats().frames, 5);
  EXPECT_EQ(stream_.stats().dropped, 0);
}

TEST_F(MockVideoStreamTest, FrameBeyondTheTimeoutIsATimeoutAtNowPlusTimeout) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame f;
  EXPECT_EQ(stream_.dequeue(2 * kMs, &f), HalStatus::kTimeout);
  EXPECT_EQ(clock_.now(), kFirst - 3 * kMs);
  EXPECT_EQ(stream_.dequeue(0, &f), HalStatus::kTimeout);  // non-blocking: time stands
  EXPECT_EQ(clock_.now(), kFirst - 3 * kMs);
  EXPECT_EQ(stream_.stats().timeouts, 2);
  ASSERT_EQ(stream_.dequeue(3 * kMs, &f), HalStatus::kOk);  // due exactly at the deadline
  EXPECT_EQ(f.stamp, kFirst);
}

TEST_F(MockVideoStreamTest, FramesWhileEveryBufferIsLentAreLostWithTheirSequenceNumbers) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame held[3];
  for (auto& f : held) ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(stream_.lent(), 3);
  // Three more frames come and go while the consumer holds everything.
  VideoFrame f;
  EXPECT_EQ(stream_.dequeue(3 * kPeriod, &f), HalStatus::kTimeout);
  EXPECT_EQ(stream_.overruns(), 3);
  EXPECT_EQ(source_.skipped, 3);
  ASSERT_EQ(stream_.release(held[0].index), HalStatus::kOk);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.sequence, 6u);
  EXPECT_EQ(f.index, held[0].index);
  EXPECT_EQ(stream_.stats().dropped, 3);
  EXPECT_EQ(stream_.stats().sequence_gaps, 1);
}

TEST_F(MockVideoStreamTest, LaggingConsumerGetsTheOldestFramesAndLosesTheNewest) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  clock_.set(kFirst + 9 * kPeriod);  // ten frames due at once, three buffers
  VideoFrame f;
  for (std::uint32_t n = 0; n < 3; ++n) {
    ASSERT_EQ(stream_.dequeue(0, &f), HalStatus::kOk);
    EXPECT_EQ(f.sequence, n);
    EXPECT_EQ(f.stamp, kFirst + static_cast<TimeNs>(n) * kPeriod);
    ASSERT_EQ(stream_.release(f.index), HalStatus::kOk);
  }
  EXPECT_EQ(stream_.overruns(), 7);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.sequence, 10u);
  EXPECT_EQ(stream_.stats().dropped, 7);
}

TEST_F(MockVideoStreamTest, SkipSequenceShowsAsAGap) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  ASSERT_EQ(stream_.release(f.index), HalStatus::kOk);
  stream_.skip_sequence(4);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.sequence, 5u);
  EXPECT_EQ(f.stamp, kFirst + kPeriod);
  EXPECT_EQ(stream_.stats().dropped, 4);
  EXPECT_EQ(stream_.stats().sequence_gaps, 1);
}

TEST_F(MockVideoStreamTest, CorruptFlagAndWrongBytesUsed) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  stream_.corrupt_next(1);
  stream_.set_next_bytes_used(7);
  VideoFrame f;
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_TRUE(f.corrupted);
  EXPECT_EQ(f.bytes_used, 7u);
  ASSERT_EQ(stream_.release(f.index), HalStatus::kOk);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_FALSE(f.corrupted);
  EXPECT_EQ(f.bytes_used, 32u);
  ASSERT_EQ(stream_.release(f.index), HalStatus::kOk);
  // Larger than the buffer: clamped and flagged, as V4l2Stream does.
  stream_.set_next_bytes_used(33);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.bytes_used, 32u);
  EXPECT_TRUE(f.corrupted);
  EXPECT_EQ(stream_.stats().corrupted, 2);
}

TEST_F(MockVideoStreamTest, SourceReportingAShortFramePassesThrough) {
  source_.bytes_used = 10;
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.bytes_used, 10u);
  EXPECT_FALSE(f.corrupted);
}

TEST_F(MockVideoStreamTest, UnplugIsClosedUntilAReopenIsAllowed) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame held;
  ASSERT_EQ(stream_.dequeue(100 * kMs, &held), HalStatus::kOk);
  stream_.unplug();
  stream_.refuse_reopens(2);
  VideoFrame f;
  EXPECT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kClosed);
  EXPECT_EQ(stream_.release(held.index), HalStatus::kClosed);
  EXPECT_EQ(stream_.start(), HalStatus::kClosed);
  EXPECT_EQ(stream_.stats().lost, 1);
  EXPECT_EQ(stream_.reopen(), HalStatus::kClosed);
  EXPECT_EQ(stream_.reopen(), HalStatus::kClosed);
  EXPECT_EQ(stream_.stats().reopen_failures, 2);
  EXPECT_EQ(stream_.dequeue(0, &f), HalStatus::kClosed);
  clock_.set(kFirst + 50 * kPeriod + kMs);  // time passes while unplugged
  ASSERT_EQ(stream_.reopen(), HalStatus::kOk);
  EXPECT_EQ(stream_.stats().reopens, 1);
  EXPECT_EQ(stream_.stats().lost, 1);
  EXPECT_EQ(stream_.lent(), 0);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.stamp, kFirst + 51 * kPeriod);  // frames due while unplugged never were
  EXPECT_EQ(f.sequence, 0u);                  // a new stream counts from 0
  EXPECT_EQ(stream_.stats().dropped, 0);
}

TEST_F(MockVideoStreamTest, FramesBeforeStartDoNotExist) {
  clock_.set(kFirst + 2 * kPeriod + kMs);
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_EQ(f.stamp, kFirst + 3 * kPeriod);
  EXPECT_EQ(f.sequence, 0u);
}

TEST_F(MockVideoStreamTest, NotStreamingAndBadReleasesAreErrors) {
  VideoFrame f;
  EXPECT_EQ(stream_.dequeue(0, &f), HalStatus::kIoError);
  EXPECT_STREQ(stream_.last_error(), "mock video: dequeue while not streaming; call start() first");
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  EXPECT_EQ(stream_.release(0), HalStatus::kIoError);
  EXPECT_EQ(stream_.release(-1), HalStatus::kIoError);
  EXPECT_EQ(stream_.release(3), HalStatus::kIoError);
  ASSERT_EQ(stream_.dequeue(100 * kMs, &f), HalStatus::kOk);
  stream_.stop();  // lent buffers go back with the stream
  EXPECT_EQ(stream_.lent(), 0);
  EXPECT_EQ(stream_.release(f.index), HalStatus::kIoError);
}

TEST(MockVideoStreamEnd, ExhaustedSourceTimesOut) {
  SimClock clock(kFirst);
  PatternSource source(2);
  MockVideoStream s(clock, source, yuyv_format(2, 2, 100, 2));
  ASSERT_EQ(s.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(s.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_FALSE(s.exhausted());
  ASSERT_EQ(s.release(f.index), HalStatus::kOk);
  ASSERT_EQ(s.dequeue(100 * kMs, &f), HalStatus::kOk);
  EXPECT_TRUE(s.exhausted());  // said so when asked after the last frame
  EXPECT_EQ(s.dequeue(100 * kMs, &f), HalStatus::kTimeout);
  EXPECT_EQ(clock.now(), kFirst + kPeriod + 100 * kMs);
}

class StuckSource final : public FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kFirst; }
  std::uint32_t fill(TimeNs, std::uint32_t, std::uint8_t*, std::uint32_t) noexcept override { return 0; }
};

TEST(MockVideoStreamEnd, SourceThatDoesNotMoveOnIsAnErrorNotAHang) {
  SimClock clock(kFirst);
  StuckSource source;
  MockVideoStream s(clock, source, yuyv_format(2, 2, 100, 2));
  ASSERT_EQ(s.start(), HalStatus::kOk);
  VideoFrame f;
  EXPECT_EQ(s.dequeue(0, &f), HalStatus::kIoError);
  EXPECT_NE(std::string(s.last_error()).find("times must increase"), std::string::npos);
}

TEST_F(MockVideoStreamTest, DequeueAndReleaseDoNotAllocate) {
  ASSERT_EQ(stream_.start(), HalStatus::kOk);
  std::size_t allocations = 0;
  int frames = 0;
  {
    test::AllocScope scope;
    VideoFrame f;
    for (int n = 0; n < 300; ++n) {
      if (n % 40 == 0) stream_.skip_sequence(2);
      if (n % 30 == 0) stream_.corrupt_next();
      if (stream_.dequeue(100 * kMs, &f) != HalStatus::kOk) break;
      ++frames;
      if (stream_.release(f.index) != HalStatus::kOk) break;
    }
    (void)stream_.release(2);
    (void)stream_.dequeue(0, &f);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(frames, 300);
  EXPECT_EQ(stream_.stats().dropped, 2 * 7);  // skips before frames 40, 80, ..., 280 (the one before frame 0 is no gap)
  EXPECT_EQ(stream_.stats().corrupted, 10);
}

}  // namespace mock_video_stream_test
}  // namespace rtfuse::hal::mock
