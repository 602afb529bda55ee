// ReplayVideoStream: a recording of a MockVideoStream (through the
// RecordingVideoStream decorator) replayed gives the driver the same calls'
// results and the same frame bytes; another call diverges with a report
// naming the log event; a frame the recorder lost is named.
#include "hal/replay/replay_video_stream.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hal/mock/mock_video_stream.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/recording_video_stream.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::hal::replay {
namespace replay_video_stream_test {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kPeriod = 10 * kMs;
constexpr TimeNs kFirst = 1'000 * kMs;

class PatternSource final : public mock::FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kFirst + taken_ * kPeriod; }
  std::uint32_t fill(TimeNs, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    ++taken_;
    for (std::uint32_t i = 0; data != nullptr && i < capacity; ++i) {
      data[i] = static_cast<std::uint8_t>(sequence * 13 + i * 3);
    }
    return capacity;
  }

 private:
  int taken_ = 0;
};

// What the "driver" saw live, to compare with the replay.
struct Seen {
  HalStatus status = HalStatus::kOk;
  int index = -1;
  TimeNs stamp = 0;
  std::uint32_t sequence = 0;
  std::uint32_t bytes_used = 0;
  bool corrupted = false;
  std::vector<std::uint8_t> bytes;
  bool operator==(const Seen& o) const {
    return status == o.status && index == o.index && stamp == o.stamp && sequence == o.sequence &&
           bytes_used == o.bytes_used && corrupted == o.corrupted && bytes == o.bytes;
  }
};

// A driver: start, n dequeues (each frame released), with a corrupted frame
// and a timeout in between.
std::vector<Seen> drive(VideoStream& s, mock::MockVideoStream* live, int n) {
  std::vector<Seen> seen;
  Seen started;
  started.status = s.start();
  seen.push_back(started);
  for (int i = 0; i < n; ++i) {
    if (live != nullptr && i == 2) live->corrupt_next();
    VideoFrame f;
    Seen x;
    x.status = s.dequeue(i == 3 ? 1 * kMs : 100 * kMs, &f);
    if (x.status == HalStatus::kOk) {
      x.index = f.index;
      x.stamp = f.stamp;
      x.sequence = f.sequence;
      x.bytes_used = f.bytes_used;
      x.corrupted = f.corrupted;
      x.bytes.assign(f.data, f.data + f.bytes_used);
      s.release(f.index);
    }
    seen.push_back(x);
  }
  return seen;
}

// Records a live drive and loads it into a log, as the loader does.
struct Recorded {
  explicit Recorded(int n, std::size_t frame_slots = 64) : ring(format.image_size, frame_slots, 256) {
    mock::SimClock clock(kFirst - 5 * kMs);
    PatternSource source;
    mock::MockVideoStream live(clock, source, format);
    RecordingVideoStream rec(live, ring, 0, &clock);
    seen = drive(rec, &live, n);
    load();
  }
  void load() {
    std::int64_t event = 1;
    bool holed = false;
    for (;;) {
      const std::uint8_t* frame = nullptr;
      const VideoEvent* ev = ring.peek(&frame);
      if (ev == nullptr) break;
      if (!holed && ev->lost_before > 0) {
        log.mark_hole(event, ev->lost_before, ev->frames_before);
        holed = true;
      }
      if (!holed) log.append(*ev, frame, event);
      ring.pop();
      ++event;
    }
  }
  VideoFormat format = mock::yuyv_format(16, 4, 100, 3);
  VideoRecordRing ring;
  ReplayVideoLog log{"camera"};
  std::vector<Seen> seen;
};

TEST(HalReplayVideoStream, ReplayGivesBackIdenticalFrames) {
  Recorded r(8);
  ReplayVideoStream replay(r.log, 0);
  EXPECT_EQ(replay.format().width, 16);
  EXPECT_EQ(replay.format().image_size, r.format.image_size);
  const std::vector<Seen> again = drive(replay, nullptr, 8);
  ASSERT_EQ(again.size(), r.seen.size());
  for (std::size_t i = 0; i < again.size(); ++i) EXPECT_TRUE(again[i] == r.seen[i]) << "call " << i;
  EXPECT_EQ(r.seen[4].status, HalStatus::kTimeout);  // the short dequeue timed out live
  EXPECT_TRUE(r.seen[3].corrupted);
  EXPECT_TRUE(r.log.at_end());
  EXPECT_FALSE(r.log.diverged());
  EXPECT_EQ(replay.stats().frames, 7);
  EXPECT_EQ(replay.stats().corrupted, 1);
  EXPECT_EQ(replay.stats().timeouts, 1);
}

TEST(HalReplayVideoStream, ReplayCallsDoNotAllocate) {
  Recorded r(8);
  ReplayVideoStream replay(r.log, 0);
  rtfuse::test::AllocScope scope;
  replay.start();
  VideoFrame f;
  replay.dequeue(100 * kMs, &f);
  replay.release(f.index);
  replay.dequeue(100 * kMs, &f);
  replay.release(0);  // diverges (the recording released another index, or dequeued): the report is fixed storage
  EXPECT_EQ(scope.count(), 0u);
}

TEST(HalReplayVideoStream, ADifferentCallDivergesWithAReport) {
  Recorded r(4);
  ReplayVideoStream replay(r.log, 0);
  ASSERT_EQ(replay.start(), HalStatus::kOk);
  VideoFrame f;
  ASSERT_EQ(replay.dequeue(100 * kMs, &f), HalStatus::kOk);
  // The recording released the buffer next; this driver dequeues again.
  EXPECT_EQ(replay.dequeue(50 * kMs, &f), HalStatus::kClosed);
  EXPECT_TRUE(r.log.diverged());
  EXPECT_EQ(r.log.divergence_kind(), DivergenceKind::kMismatch);
  EXPECT_EQ(r.log.divergence_event(), 3);
  EXPECT_STREQ(r.log.divergence(),
               ("event 3: recorded release index " + std::to_string(r.seen[1].index) +
                ", driver called dequeue timeout 50000000 ns")
                   .c_str());
  EXPECT_STREQ(replay.last_error(), r.log.divergence());
  EXPECT_EQ(replay.release(0), HalStatus::kClosed);  // everything after fails
}

TEST(HalReplayVideoStream, ADifferentTimeoutOrIndexDiverges) {
  {
    Recorded r(2);
    ReplayVideoStream replay(r.log, 0);
    replay.start();
    VideoFrame f;
    EXPECT_EQ(replay.dequeue(99 * kMs, &f), HalStatus::kClosed);
    EXPECT_STREQ(r.log.divergence(),
                 "event 2: recorded dequeue timeout 100000000 ns, driver called dequeue timeout 99000000 ns");
  }
  {
    Recorded r(2);
    ReplayVideoStream replay(r.log, 0);
    replay.start();
    VideoFrame f;
    ASSERT_EQ(replay.dequeue(100 * kMs, &f), HalStatus::kOk);
    EXPECT_EQ(replay.release(f.index + 1), HalStatus::kClosed);
    EXPECT_NE(std::string(r.log.divergence()).find("recorded release index"), std::string::npos);
  }
}

TEST(HalReplayVideoStream, EndOfStreamIsReported) {
  Recorded r(1);
  ReplayVideoStream replay(r.log, 0);
  drive(replay, nullptr, 1);
  EXPECT_TRUE(r.log.at_end());
  VideoFrame f;
  EXPECT_EQ(replay.dequeue(100 * kMs, &f), HalStatus::kClosed);
  EXPECT_EQ(r.log.divergence_kind(), DivergenceKind::kEndOfStream);
  EXPECT_STREQ(r.log.divergence(),
               "stream 'camera' ended after event 3 (3 calls replayed): driver called dequeue on device 0 "
               "timeout 100000000 ns");
  EXPECT_TRUE(r.log.at_end());  // a clean end, not a mismatch
}

TEST(HalReplayVideoStream, ALostFrameIsNamed) {
  // Two frame slots, never drained while recording: frames 2.. are lost.
  Recorded r(6, /*frame_slots=*/2);
  EXPECT_TRUE(r.log.has_hole());
  EXPECT_EQ(r.log.first_lost_frame(), 2);
  EXPECT_EQ(r.log.frames(), 2);
  ReplayVideoStream replay(r.log, 0);
  const std::vector<Seen> again = drive(replay, nullptr, 6);
  EXPECT_TRUE(again[1] == r.seen[1]);
  EXPECT_TRUE(again[2] == r.seen[2]);
  EXPECT_EQ(again[3].status, HalStatus::kClosed);
  EXPECT_EQ(r.log.divergence_kind(), DivergenceKind::kEndOfStream);
  const std::string report = r.log.divergence();
  EXPECT_NE(report.find("frame 2 of stream camera was not recorded: the recorder's ring was full"),
            std::string::npos)
      << report;
}

}  // namespace replay_video_stream_test
}  // namespace rtfuse::hal::replay
