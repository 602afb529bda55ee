// StereoCamera on a MockVideoStream and a SimClock: frames rectified into the
// pool with the capture stamp and sequence, gaps counted, bad frames refused
// (never rectified, buffer given back), unplug and reopen with doubling
// backoff and no busy loop, a full pool dropping and counting, format and
// calibration mismatches refused at create with a clear message, no
// allocation per step, the digest of the published pairs. And the USB 2 hint
// for a refused open.
#include "drivers/camera/stereo_camera.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/frame_pool.hpp"
#include "drivers/camera/zed_usb_hint.hpp"
#include "hal/mock/frame_generator.hpp"
#include "hal/mock/mock_video_stream.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace stereo_camera_test {

using rtfuse::FramePool;
using rtfuse::TimeNs;
using rtfuse::drivers::StereoCamera;
using rtfuse::drivers::StereoCameraConfig;
using rtfuse::drivers::StereoFrameResult;
using rtfuse::drivers::StereoStepOutcome;
namespace hal = rtfuse::hal;
namespace drivers = rtfuse::drivers;

constexpr int kEyeW = 672;  // VGA
constexpr int kEyeH = 376;
constexpr TimeNs kStart = 1'000'000'000;
constexpr TimeNs kPeriod = 10'000'000;  // 100 fps
constexpr TimeNs kMs = 1'000'000;

std::uint8_t luma(std::uint32_t seq, int eye, int x, int y) {
  return static_cast<std::uint8_t>(seq * 29u + static_cast<std::uint32_t>(eye * 101 + x * 3 + y * 7));
}

// Side-by-side YUYV of 2 x kEyeW by kEyeH whose luma depends on the sequence
// number, so a stale or mixed frame shows; chroma bytes are extreme so that
// chroma leaking into the grey output would show too.
void paint(std::uint32_t seq, std::uint8_t* data) {
  for (int y = 0; y < kEyeH; ++y) {
    for (int x = 0; x < 2 * kEyeW; ++x) {
      std::uint8_t* p = data + (static_cast<std::size_t>(y) * 2 * kEyeW + static_cast<std::size_t>(x)) * 2;
      p[0] = luma(seq, x / kEyeW, x % kEyeW, y);
      p[1] = (x & 1) ? 0xFF : 0x00;
    }
  }
}

// A frame every kPeriod from kStart, painted with paint().
class PatternSource final : public hal::mock::FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kStart + static_cast<TimeNs>(taken_) * kPeriod; }
  std::uint32_t fill(TimeNs, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    ++taken_;
    if (data == nullptr) {
      ++lost_;
      return 0;
    }
    paint(sequence, data);
    return capacity;
  }
  std::int64_t lost() const { return lost_; }

 private:
  std::int64_t taken_ = 0;
  std::int64_t lost_ = 0;
};

// Forwards to the mock and records when reopen() was called.
class ReopenTimes final : public hal::VideoStream {
 public:
  ReopenTimes(hal::VideoStream& s, hal::Clock& c) : s_(s), c_(c) { times.reserve(64); }
  const hal::VideoFormat& format() const noexcept override { return s_.format(); }
  hal::HalStatus start() noexcept override { return s_.start(); }
  void stop() noexcept override { s_.stop(); }
  hal::HalStatus dequeue(TimeNs t, hal::VideoFrame* f) noexcept override { return s_.dequeue(t, f); }
  hal::HalStatus release(int i) noexcept override { return s_.release(i); }
  hal::HalStatus reopen() noexcept override {
    times.push_back(c_.now());
    return s_.reopen();
  }
  const hal::VideoStreamStats& stats() const noexcept override { return s_.stats(); }
  const char* last_error() const noexcept override { return s_.last_error(); }
  std::vector<TimeNs> times;

 private:
  hal::VideoStream& s_;
  hal::Clock& c_;
};

StereoCameraConfig vga_config() {
  StereoCameraConfig c;
  c.resolution = "VGA";
  c.fps = 100;
  c.calibration = rtfuse::test::zed_like_vga();
  c.reopen_backoff_initial_ns = 100 * kMs;
  c.reopen_backoff_max_ns = 400 * kMs;
  return c;
}

struct Rig {
  hal::mock::SimClock clock{kStart - kPeriod / 2};
  PatternSource source;
  hal::mock::MockVideoStream stream;
  FramePool pool;
  std::unique_ptr<StereoCamera> camera;
  std::string error;
  explicit Rig(int pool_slots = 4, StereoCameraConfig config = vga_config())
      : stream(clock, source, hal::mock::yuyv_format(2 * kEyeW, kEyeH, 100)), pool(pool_slots, kEyeW, kEyeH) {
    camera = StereoCamera::create(config, stream, clock, pool, &error);
  }
};

// What the camera must publish for sequence seq: the rectifier, built here
// independently from the same calibration, run on the same frame.
struct Reference {
  drivers::StereoRectification rect;
  std::unique_ptr<drivers::StereoRectifier> rectifier;
  std::vector<std::uint8_t> frame, left, right;
  Reference() : frame(static_cast<std::size_t>(4 * kEyeW * kEyeH)), left(kEyeW * kEyeH), right(kEyeW * kEyeH) {
    std::string e;
    EXPECT_TRUE(drivers::compute_stereo_rectification(rtfuse::test::zed_like_vga(), &rect, &e)) << e;
    rectifier = std::make_unique<drivers::StereoRectifier>(rtfuse::test::zed_like_vga(), rect);
  }
  // The rectified frame seq into left and right (rows kEyeW apart).
  void rectify(std::uint32_t seq) {
    paint(seq, frame.data());
    EXPECT_TRUE(rectifier->rectify({frame.data(), frame.size(), 2 * kEyeW, kEyeH, 4 * kEyeW},
                                   {left.data(), kEyeW}, {right.data(), kEyeW}));
  }
  // True when f holds exactly the rectified frame seq.
  bool matches(const FramePool::Frame& f, std::uint32_t seq) {
    rectify(seq);
    for (int y = 0; y < kEyeH; ++y) {
      if (std::memcmp(f.left + y * f.stride, left.data() + y * kEyeW, kEyeW) != 0) return false;
      if (std::memcmp(f.right + y * f.stride, right.data() + y * kEyeW, kEyeW) != 0) return false;
    }
    return true;
  }
};

TEST(StereoCamera, FramesComeOutRectifiedWithStampAndSequence) {
  Rig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  EXPECT_TRUE(rig.stream.streaming());
  Reference ref;
  for (std::uint32_t i = 0; i < 3; ++i) {
    StereoFrameResult r;
    ASSERT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame) << rig.camera->stats().last_error;
    EXPECT_EQ(r.published, 1);
    EXPECT_EQ(r.sequence, i);
    EXPECT_EQ(r.stamp, kStart + static_cast<TimeNs>(i) * kPeriod);
    FramePool::Handle h = rig.pool.take_latest();
    ASSERT_TRUE(h.valid());
    const FramePool::Frame f = rig.pool.frame(h);
    EXPECT_EQ(f.frame_id, r.frame_id);
    EXPECT_EQ(f.sequence, i);
    EXPECT_EQ(f.stamp, r.stamp);
    EXPECT_TRUE(ref.matches(f, i)) << "frame " << i;
    rig.pool.release(h);
    EXPECT_EQ(rig.stream.lent(), 0);  // the buffer went straight back
  }
  const auto& s = rig.camera->stats();
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.rectified, 3);
  EXPECT_EQ(s.stream.frames, 3);
  EXPECT_EQ(s.rate_frames, 3);
  EXPECT_DOUBLE_EQ(s.measured_fps(), 100.0);
  // Consumers get the rectified pinhole and baseline.
  EXPECT_NEAR(rig.camera->rectified().baseline_m, 0.119997, 1e-4);
  EXPECT_GT(rig.camera->rectified().fx, 0.0);
}

TEST(StereoCamera, TimeoutWhenNothingComes) {
  Rig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  StereoFrameResult r;
  EXPECT_EQ(rig.camera->step(kPeriod / 4, &r), StereoStepOutcome::kTimeout);
  EXPECT_EQ(r.published, 0);
  EXPECT_EQ(rig.camera->stats().stream.timeouts, 1);
}

TEST(StereoCamera, SequenceGapsAreCounted) {
  Rig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  StereoFrameResult r;
  ASSERT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  rig.stream.skip_sequence(3);
  ASSERT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  EXPECT_EQ(r.sequence, 4u);
  EXPECT_EQ(r.dropped, 3);
  EXPECT_EQ(rig.camera->stats().stream.dropped, 3);
  EXPECT_EQ(rig.camera->stats().stream.sequence_gaps, 1);
}

TEST(StereoCamera, WrongBytesUsedIsRejectedNotRectified) {
  Rig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  rig.stream.set_next_bytes_used(4 * kEyeW * kEyeH - 4096);
  StereoFrameResult r;
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kRejected);
  EXPECT_EQ(r.published, 0);
  EXPECT_EQ(rig.camera->stats().rejected_size, 1);
  EXPECT_EQ(rig.camera->stats().rectified, 0);
  EXPECT_EQ(rig.pool.published(), 0);
  EXPECT_FALSE(rig.pool.take_latest().valid());
  EXPECT_EQ(rig.stream.lent(), 0);
  EXPECT_NE(std::string(rig.camera->stats().last_error).find("expected"), std::string::npos);
  // The next good frame goes through.
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  EXPECT_EQ(r.sequence, 1u);
}

TEST(StereoCamera, CorruptedFrameIsRejected) {
  Rig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  rig.stream.corrupt_next(2);
  StereoFrameResult r;
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kRejected);
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kRejected);
  EXPECT_EQ(rig.camera->stats().rejected_corrupted, 2);
  EXPECT_EQ(rig.pool.published(), 0);
  EXPECT_EQ(rig.stream.lent(), 0);
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
}

TEST(StereoCamera, UnplugThenReopenAtDoublingCappedBackoffThenRecovery) {
  hal::mock::SimClock clock{kStart - kPeriod / 2};
  PatternSource source;
  hal::mock::MockVideoStream mock(clock, source, hal::mock::yuyv_format(2 * kEyeW, kEyeH, 100));
  ReopenTimes stream(mock, clock);
  FramePool pool(4, kEyeW, kEyeH);
  std::string error;
  auto camera = StereoCamera::create(vga_config(), stream, clock, pool, &error);
  ASSERT_TRUE(camera) << error;
  StereoFrameResult r;
  ASSERT_EQ(camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);

  mock.unplug();
  mock.refuse_reopens(4);
  const TimeNs lost_at = clock.now();
  ASSERT_EQ(camera->step(kPeriod * 2, &r), StereoStepOutcome::kLost);
  EXPECT_TRUE(camera->down());
  EXPECT_EQ(camera->stats().lost, 1);
  EXPECT_EQ(camera->stats().stream.lost, 1);

  // Short steps while down: every one must move the clock (no busy loop)
  // and reopen() is only called at the backoff deadlines.
  int steps = 0;
  StereoStepOutcome o = StereoStepOutcome::kDown;
  while (o != StereoStepOutcome::kReopened && steps < 1000) {
    const TimeNs before = clock.now();
    o = camera->step(30 * kMs, &r);
    ++steps;
    if (o == StereoStepOutcome::kDown) {
      ASSERT_GT(clock.now(), before) << "a down step returned without waiting";
    }
  }
  ASSERT_EQ(o, StereoStepOutcome::kReopened);
  // 100, 200, 400, 400 (capped) ms apart; the fifth attempt succeeds.
  const std::vector<TimeNs> want = {lost_at + 100 * kMs, lost_at + 300 * kMs, lost_at + 700 * kMs,
                                    lost_at + 1100 * kMs, lost_at + 1500 * kMs};
  EXPECT_EQ(stream.times, want);
  EXPECT_LE(steps, 1500 / 30 + 6);  // bounded by the step timeout, not spinning
  EXPECT_FALSE(camera->down());
  EXPECT_EQ(camera->stats().stream.reopen_failures, 4);
  EXPECT_EQ(camera->stats().stream.reopens, 1);
  EXPECT_EQ(camera->stats().reopen_attempts, 5);
  EXPECT_EQ(camera->reopen_backoff_ns(), 100 * kMs);  // reset by the success

  // Frames flow again; the device counts from 0 after a restart.
  ASSERT_EQ(camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame) << camera->stats().last_error;
  EXPECT_EQ(r.sequence, 0u);
  EXPECT_GT(r.stamp, lost_at + 1500 * kMs - kPeriod);
  EXPECT_EQ(camera->stats().rate_frames, 1);  // rate restarts after the gap

  // A second loss starts again at the initial backoff.
  mock.unplug();
  const TimeNs lost2 = clock.now();
  ASSERT_EQ(camera->step(kPeriod * 2, &r), StereoStepOutcome::kLost);
  EXPECT_EQ(camera->next_reopen_ns(), lost2 + 100 * kMs);
  // A long step sleeps until the deadline, then reopens.
  EXPECT_EQ(camera->step(1000 * kMs, &r), StereoStepOutcome::kReopened);
  EXPECT_EQ(stream.times.back(), lost2 + 100 * kMs);
}

TEST(StereoCamera, FullPoolDropsTheFrameAndCountsIt) {
  Rig rig(2);
  ASSERT_TRUE(rig.camera) << rig.error;
  StereoFrameResult r;
  ASSERT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  FramePool::Handle a = rig.pool.take_latest();
  ASSERT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  FramePool::Handle b = rig.pool.take_latest();
  // Both slots held by consumers: the third frame has nowhere to go.
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kPoolFull);
  EXPECT_EQ(rig.camera->stats().pool_full, 1);
  EXPECT_EQ(rig.pool.dropped_full(), 1);
  EXPECT_EQ(rig.stream.lent(), 0);
  EXPECT_EQ(rig.pool.frame(a).sequence, 0u);  // untouched while held
  EXPECT_EQ(rig.pool.frame(b).sequence, 1u);
  rig.pool.release(a);
  EXPECT_EQ(rig.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  EXPECT_EQ(r.sequence, 3u);
  rig.pool.release(b);
}

TEST(StereoCamera, CatchUpTakesQueuedFramesWithoutCountingTimeouts) {
  StereoCameraConfig c = vga_config();
  c.max_frames_per_step = 4;
  Rig rig(4, c);
  ASSERT_TRUE(rig.camera) << rig.error;
  rig.clock.sleep_until(kStart + 2 * kPeriod);  // three frames are waiting
  StereoFrameResult r;
  ASSERT_EQ(rig.camera->step(0, &r), StereoStepOutcome::kFrame);
  EXPECT_EQ(r.published, 3);
  EXPECT_EQ(r.sequence, 2u);
  EXPECT_EQ(rig.camera->stats().stream.timeouts, 0);
}

TEST(StereoCamera, FormatMismatchAtCreateIsAClearError) {
  hal::mock::SimClock clock;
  PatternSource source;
  FramePool pool(2, kEyeW, kEyeH);
  std::string error;
  {
    hal::mock::MockVideoStream hd(clock, source, hal::mock::yuyv_format(2560, 720, 100));
    EXPECT_FALSE(StereoCamera::create(vga_config(), hd, clock, pool, &error));
    EXPECT_NE(error.find("YUYV 2560x720"), std::string::npos) << error;
    EXPECT_NE(error.find("needs YUYV 1344x376"), std::string::npos) << error;
    EXPECT_FALSE(hd.streaming());
  }
  {
    hal::VideoFormat grey = hal::mock::yuyv_format(2 * kEyeW, kEyeH, 100);
    grey.pixel_format = hal::kFourccGrey;
    hal::mock::MockVideoStream s(clock, source, grey);
    EXPECT_FALSE(StereoCamera::create(vga_config(), s, clock, pool, &error));
    EXPECT_NE(error.find("GREY 1344x376"), std::string::npos) << error;
  }
  hal::mock::MockVideoStream ok(clock, source, hal::mock::yuyv_format(2 * kEyeW, kEyeH, 100));
  {
    StereoCameraConfig c = vga_config();
    c.calibration = rtfuse::test::zed_like_hd();
    EXPECT_FALSE(StereoCamera::create(c, ok, clock, pool, &error));
    EXPECT_NE(error.find("calibration is for 1280x720"), std::string::npos) << error;
  }
  {
    StereoCameraConfig c = vga_config();
    c.expected_serial = 12345;
    c.calibration_serial = 999;
    EXPECT_FALSE(StereoCamera::create(c, ok, clock, pool, &error));
    EXPECT_NE(error.find("SN12345.conf"), std::string::npos) << error;
  }
  {
    StereoCameraConfig c = vga_config();
    c.fps = 120;
    EXPECT_FALSE(StereoCamera::create(c, ok, clock, pool, &error));
    EXPECT_NE(error.find("VGA@15/30/60/100"), std::string::npos) << error;
  }
  {
    FramePool small(2, 320, 240);
    EXPECT_FALSE(StereoCamera::create(vga_config(), ok, clock, small, &error));
    EXPECT_NE(error.find("frame pool"), std::string::npos) << error;
  }
  EXPECT_FALSE(ok.streaming());
  EXPECT_TRUE(StereoCamera::create(vga_config(), ok, clock, pool, &error)) << error;
}

TEST(StereoCamera, StepDoesNotAllocateInSteadyState) {
  Rig rig(3);
  ASSERT_TRUE(rig.camera) << rig.error;
  StereoFrameResult r;
  for (int i = 0; i < 3; ++i) rig.camera->step(kPeriod * 2, &r);
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 40; ++i) {
    if (i == 10) rig.stream.skip_sequence(2);
    if (i == 20) rig.stream.corrupt_next();
    if (i == 30) rig.stream.set_next_bytes_used(100);
    rig.camera->step(kPeriod * 2, &r);
    FramePool::Handle h = rig.pool.take_latest();
    rig.pool.release(h);
  }
  rig.camera->step(kPeriod / 4, &r);  // a timeout too
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(rig.camera->stats().rectified, 3 + 38);
}

// --- the digest of the published pairs ---

// Two 8 x 4 eyes whose rows are 16 bytes apart; the padding is not image.
struct SmallPair {
  static constexpr int kW = 8, kH = 4, kStride = 16;
  std::vector<std::uint8_t> left = std::vector<std::uint8_t>(kStride * kH, 0xEE);
  std::vector<std::uint8_t> right = std::vector<std::uint8_t>(kStride * kH, 0xEE);
  SmallPair() {
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        left[static_cast<std::size_t>(y * kStride + x)] = static_cast<std::uint8_t>(y * 16 + x);
        right[static_cast<std::size_t>(y * kStride + x)] = static_cast<std::uint8_t>(200 - 3 * (y * kW + x));
      }
    }
  }
  std::uint64_t chain(std::uint64_t previous) const {
    return drivers::chain_pair_digest(previous, left.data(), right.data(), kW, kH, kStride);
  }
};

// Written down once (and equal to the reference libxxhash's XXH64 of the
// left rows then the right rows): a machine that computes another value
// fails here, the aarch64 stage included.
TEST(PairDigest, KnownAnswer) {
  const SmallPair p;
  const std::uint64_t first = p.chain(0);
  EXPECT_EQ(first, 0x8E61C3FBECB0BD50ULL);
  // The eyes swapped, chained after the first.
  EXPECT_EQ(drivers::chain_pair_digest(first, p.right.data(), p.left.data(), SmallPair::kW, SmallPair::kH,
                                       SmallPair::kStride),
            0xC22E354251EF0A04ULL);
}

TEST(PairDigest, OneByteOfOneEyeChangesItThePaddingDoesNot) {
  SmallPair p;
  const std::uint64_t base = p.chain(0);
  EXPECT_EQ(SmallPair().chain(0), base) << "the same pair, the same digest";
  for (auto* eye : {&p.left, &p.right}) {
    for (int y = 0; y < SmallPair::kH; ++y) {
      for (int x = 0; x < SmallPair::kW; ++x) {
        std::uint8_t& b = (*eye)[static_cast<std::size_t>(y * SmallPair::kStride + x)];
        b ^= 0x10;
        EXPECT_NE(p.chain(0), base) << (eye == &p.left ? "left" : "right") << " x " << x << " y " << y;
        b ^= 0x10;
      }
    }
  }
  p.left[SmallPair::kW] = 0x00;  // padding after the first row
  p.right[SmallPair::kStride * SmallPair::kH - 1] = 0x00;
  EXPECT_EQ(p.chain(0), base);
}

TEST(PairDigest, TheSameFramesGiveTheSameDigestInTheirOrderOnly) {
  const SmallPair a;
  SmallPair b;
  b.right[3] = 0x42;
  const std::uint64_t ab = b.chain(a.chain(0));
  EXPECT_EQ(b.chain(a.chain(0)), ab);
  EXPECT_NE(a.chain(b.chain(0)), ab) << "order";
  EXPECT_NE(a.chain(a.chain(0)), ab);
  EXPECT_NE(b.chain(a.chain(b.chain(0))), ab) << "one pair more";
}

// The camera's digest covers exactly the pixels it published (the pool's
// row padding excluded), in publish order, and no refused frame.
TEST(StereoCamera, PairsDigestChainsEveryPublishedPair) {
  Reference ref;
  auto expected = [&](std::initializer_list<std::uint32_t> sequences) {
    std::uint64_t d = 0;
    for (std::uint32_t seq : sequences) {
      ref.rectify(seq);
      d = drivers::chain_pair_digest(d, ref.left.data(), ref.right.data(), kEyeW, kEyeH, kEyeW);
    }
    return d;
  };
  Rig a;
  Rig b;
  Rig c;
  ASSERT_TRUE(a.camera && b.camera && c.camera) << a.error;
  ASSERT_NE(a.pool.stride(), kEyeW) << "the test wants padded pool rows";
  EXPECT_EQ(a.camera->stats().pairs_digest, 0u);
  StereoFrameResult r;
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(a.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
    ASSERT_EQ(b.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  }
  EXPECT_EQ(a.camera->stats().pairs_digest, expected({0, 1, 2}));
  EXPECT_EQ(b.camera->stats().pairs_digest, a.camera->stats().pairs_digest) << "same frames, same digest";
  c.stream.corrupt_next();
  EXPECT_EQ(c.camera->step(kPeriod * 2, &r), StereoStepOutcome::kRejected);
  EXPECT_EQ(c.camera->stats().pairs_digest, 0u);
  for (int i = 0; i < 3; ++i) ASSERT_EQ(c.camera->step(kPeriod * 2, &r), StereoStepOutcome::kFrame);
  EXPECT_EQ(c.camera->stats().pairs_digest, expected({1, 2, 3}));
}

// --- the USB 2 hint ---

drivers::CameraMode mode(const char* res, int fps) {
  drivers::CameraMode m;
  std::string e;
  EXPECT_TRUE(drivers::find_camera_mode(res, fps, &m, &e)) << e;
  return m;
}

TEST(ZedUsbHint, OnlyVgaOfferedForHdLooksLikeUsb2) {
  const std::string hint =
      drivers::zed_usb2_hint(mode("HD", 30), hal::VideoFormat{}, "YUYV 1344x376 @15/30/60/100; also MJPG");
  EXPECT_NE(hint.find("USB 2"), std::string::npos) << hint;
  EXPECT_NE(hint.find("USB 3"), std::string::npos) << hint;
  EXPECT_NE(hint.find("\"VGA\""), std::string::npos) << hint;
  EXPECT_NE(hint.find("HD (2560x720)"), std::string::npos) << hint;
  EXPECT_NE(hint.find("1344x376"), std::string::npos) << hint;
  // YUYV need not come first.
  EXPECT_TRUE(drivers::looks_like_usb2(mode("2K", 15), {}, "MJPG 2560x720 @30; YUYV 1344x376 @15/30"));
}

TEST(ZedUsbHint, NotUsb2WhenBiggerModesAreOfferedOrVgaWasAsked) {
  EXPECT_EQ(drivers::zed_usb2_hint(mode("HD", 30), {}, "YUYV 1344x376 @15/30/60/100, 2560x720 @15/30/60"), "");
  EXPECT_FALSE(drivers::looks_like_usb2(mode("VGA", 30), {}, "YUYV 1344x376 @15/30/60/100"));
  // Not a ZED at all: only small unrelated sizes.
  EXPECT_FALSE(drivers::looks_like_usb2(mode("HD", 30), {}, "YUYV 640x480 @30, 320x240 @30"));
  // A stepwise range up to a big size is not VGA-only.
  EXPECT_FALSE(drivers::looks_like_usb2(mode("HD", 30), {}, "YUYV 16x16..4416x1242/2x2 @1..100"));
  // "also YUYV" names no sizes; fall back to what the device gave.
  EXPECT_FALSE(drivers::looks_like_usb2(mode("HD", 30), {}, "MJPG 1280x720 @30; also YUYV"));
}

TEST(ZedUsbHint, WithoutAnOfferListTheGivenFormatDecides) {
  hal::VideoFormat given = hal::mock::yuyv_format(1344, 376, 30);
  EXPECT_TRUE(drivers::looks_like_usb2(mode("FHD", 30), given, ""));
  given.width = 2560;
  given.height = 720;
  EXPECT_FALSE(drivers::looks_like_usb2(mode("FHD", 30), given, ""));
}

}  // namespace stereo_camera_test
