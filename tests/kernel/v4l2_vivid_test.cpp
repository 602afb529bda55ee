// The V4L2 backend (hal/linux/v4l2_stream) against the kernel's own virtual
// video driver, vivid, on a real kernel: run inside Debian's kernel under
// qemu by kernel_vm.sh (see CMakeLists.txt for the module options: two
// instances, capture nodes only).
//
// What vivid does that the tests lean on (Debian 12, kernel 6.1):
// - inputs 0..3 are Webcam, TV, S-Video, HDMI. The webcam has discrete sizes
//   (320x180 .. 3840x2160) and rates; the others scale to any size, and the
//   HDMI input is progressive with its rate fixed by the DV timings (S_PARM
//   answers with that rate): 1280x720p30 timings give a 30 fps input that
//   scales to a side-by-side stereo 1344x376. The input and timings are
//   device state that outlives a file handle, set here with raw ioctls.
// - the frame counter runs on time, not on buffers: frames due while no
//   buffer is queued are skipped in the sequence, as a real camera drops.
// - the "Disconnect" button control unregisters the instance's nodes: every
//   ioctl then fails with ENODEV and open() too, but the /dev node stays.
//   When the last file handle on the instance closes, vivid registers the
//   nodes again ("reconnect"), so a reopen after everyone let go recovers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include "core/time.hpp"
#include "hal/linux/v4l2_stream.hpp"
#include "vivid_node.hpp"

namespace {

using rtfuse::TimeNs;
using rtfuse::monotonic_now_ns;
using rtfuse::hal::HalStatus;
using rtfuse::hal::V4l2Stream;
using rtfuse::hal::VideoFrame;
using rtfuse::hal::VideoRequest;
using rtfuse::kernel_test::find_node;
using rtfuse::kernel_test::has;
using rtfuse::kernel_test::RawNode;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSecond = 1'000'000'000;
// Frames come every 33 ms; the guest runs emulated (TCG), so be generous.
constexpr TimeNs kFrameWait = 3 * kSecond;

constexpr int kStereoWidth = 1344;  // two 672x376 eyes side by side (ZED VGA)
constexpr int kStereoHeight = 376;
constexpr int kFps = 30;

VideoRequest stereo_request() {
  VideoRequest r;
  r.pixel_format = rtfuse::hal::kFourccYuyv;
  r.width = kStereoWidth;
  r.height = kStereoHeight;
  r.fps = kFps;
  r.buffers = 4;
  return r;
}

// Each test starts from vivid-NNN-vid-cap on its HDMI input at 720p30.
class VividTest : public ::testing::Test {
 protected:
  void use_instance(const char* node_name) {
    path_ = find_node(node_name);
    ASSERT_FALSE(path_.empty()) << "no V4L2 node named " << node_name
                                << " under /sys/class/video4linux: is vivid loaded with two instances and capture "
                                   "nodes (modprobe vivid n_devs=2 node_types=0x1,0x1)? This test runs inside "
                                   "tests/kernel/kernel_vm.sh (ctest -L kernel)";
    RawNode node(path_);
    ASSERT_TRUE(node.ok()) << node.error();
    ASSERT_TRUE(node.select_input("HDMI")) << node.error();
    ASSERT_TRUE(node.set_hdmi_720p30()) << node.error();
  }

  std::unique_ptr<V4l2Stream> open_stereo() {
    std::string error;
    auto s = V4l2Stream::open(path_, stereo_request(), &error);
    EXPECT_NE(s, nullptr) << error;
    return s;
  }

  std::string path_;
};

class Vivid0 : public VividTest {
 protected:
  void SetUp() override { use_instance("vivid-000-vid-cap"); }
};

// Dequeues one frame and checks what every frame must hold.
void dequeue_ok(V4l2Stream& s, VideoFrame* f) {
  const HalStatus st = s.dequeue(kFrameWait, f);
  ASSERT_EQ(st, HalStatus::kOk) << rtfuse::hal::to_string(st) << ": " << s.last_error();
  ASSERT_GE(f->index, 0);
  ASSERT_NE(f->data, nullptr);
  EXPECT_EQ(f->bytes_used, s.format().image_size);
  EXPECT_GE(f->length, s.format().image_size);
  EXPECT_FALSE(f->corrupted);
}

TEST_F(Vivid0, NegotiatesSideBySideYuyvAt30Fps) {
  auto s = open_stereo();
  ASSERT_NE(s, nullptr);
  const auto& f = s->format();
  EXPECT_EQ(f.pixel_format, rtfuse::hal::kFourccYuyv);
  EXPECT_EQ(f.width, kStereoWidth);
  EXPECT_EQ(f.height, kStereoHeight);
  EXPECT_GE(f.bytes_per_line, kStereoWidth * 2);
  EXPECT_GE(f.image_size, static_cast<std::uint32_t>(f.bytes_per_line * kStereoHeight));
  // vivid gives the timings' own fraction (742500/24750), not 30/1.
  ASSERT_GT(f.fps_denominator, 0u);
  EXPECT_EQ(f.fps_numerator % f.fps_denominator, 0u) << f.fps_numerator << "/" << f.fps_denominator;
  EXPECT_EQ(f.fps_numerator / f.fps_denominator, static_cast<std::uint32_t>(kFps));
  EXPECT_EQ(f.buffers, 4);
}

TEST_F(Vivid0, StreamsFramesStampedOnTheMonotonicClockInSequence) {
  auto s = open_stereo();
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->start(), HalStatus::kOk) << s->last_error();
  constexpr int kFrames = 20;
  TimeNs last_stamp = 0;
  std::uint32_t first_seq = 0, last_seq = 0;
  std::int64_t gaps_seen = 0;
  TimeNs max_ahead = 0;
  for (int i = 0; i < kFrames; ++i) {
    VideoFrame f;
    ASSERT_NO_FATAL_FAILURE(dequeue_ok(*s, &f));
    // The kernel's stamp on CLOCK_MONOTONIC, not decades away as a
    // CLOCK_REALTIME one would be. A clock check, not a latency bound (the
    // guest is emulated); and not "before now": vivid stamps the planned end
    // of the frame period by default (its "Timestamp Source" control), which
    // lies up to a frame period or so after the buffer is handed over.
    const TimeNs off = monotonic_now_ns() - f.stamp;
    EXPECT_LT(off < 0 ? -off : off, 10 * kSecond) << "frame " << i << ": stamp not on CLOCK_MONOTONIC?";
    max_ahead = std::max(max_ahead, -off);
    if (i > 0) {
      EXPECT_GT(f.stamp, last_stamp) << "frame " << i;
      EXPECT_GT(f.sequence, last_seq) << "frame " << i;
      gaps_seen += f.sequence - last_seq - 1;
    } else {
      first_seq = f.sequence;
    }
    // Colour bars, not an untouched buffer: the bytes differ along a line.
    bool varies = false;
    for (int x = 1; x < s->format().bytes_per_line && !varies; ++x) varies = f.data[x] != f.data[0];
    EXPECT_TRUE(varies) << "frame " << i << " holds one byte value throughout its first line";
    last_stamp = f.stamp;
    last_seq = f.sequence;
    ASSERT_EQ(s->release(f.index), HalStatus::kOk) << s->last_error();
  }
  const auto& st = s->stats();
  EXPECT_EQ(st.frames, kFrames);
  // The backend's drop count is the sequence's own: the emulated guest may
  // miss a frame or two, but the count must agree with the numbers.
  EXPECT_EQ(st.dropped, gaps_seen) << "sequence " << first_seq << ".." << last_seq;
  EXPECT_EQ(st.dropped, static_cast<std::int64_t>(last_seq - first_seq) - (kFrames - 1));
  EXPECT_EQ(st.corrupted, 0);
  EXPECT_EQ(st.lost, 0);
  std::printf("streamed %d frames %dx%d, sequence %u..%u, %lld dropped, stamps up to %.1f ms after dequeue\n",
              kFrames, s->format().width, s->format().height, first_seq, last_seq,
              static_cast<long long>(st.dropped), static_cast<double>(max_ahead) / kMs);
}

TEST_F(Vivid0, CountsFramesDroppedWhileEveryBufferIsHeld) {
  auto s = open_stereo();
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->start(), HalStatus::kOk) << s->last_error();
  const int n = s->format().buffers;
  int held[rtfuse::hal::kMaxVideoBuffers];
  std::uint32_t last_seq = 0;
  for (int i = 0; i < n; ++i) {
    VideoFrame f;
    ASSERT_NO_FATAL_FAILURE(dequeue_ok(*s, &f));
    held[i] = f.index;
    last_seq = f.sequence;
  }
  // Every buffer lent: the device has nowhere to write, nothing can come.
  VideoFrame none;
  EXPECT_EQ(s->dequeue(200 * kMs, &none), HalStatus::kTimeout) << s->last_error();
  EXPECT_EQ(s->stats().timeouts, 1);
  // A second at 30 fps: about thirty frames fall due with no buffer to fill.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const auto before = s->stats();
  for (int i = 0; i < n; ++i) ASSERT_EQ(s->release(held[i]), HalStatus::kOk) << s->last_error();
  VideoFrame f;
  ASSERT_NO_FATAL_FAILURE(dequeue_ok(*s, &f));
  ASSERT_GT(f.sequence, last_seq + 1) << "vivid's sequence did not advance while every buffer was held";
  const std::int64_t gap = f.sequence - last_seq - 1;
  EXPECT_EQ(s->stats().dropped - before.dropped, gap);
  EXPECT_EQ(s->stats().sequence_gaps - before.sequence_gaps, 1);
  std::printf("held %d buffers for 1 s: sequence %u -> %u, %lld frames counted as dropped\n", n, last_seq,
              f.sequence, static_cast<long long>(gap));
  EXPECT_EQ(s->release(f.index), HalStatus::kOk);
}

TEST_F(Vivid0, RefusesAFormatTheDeviceDoesNotOfferAndSaysWhatItOffers) {
  std::string error;
  VideoRequest r = stereo_request();
  r.pixel_format = rtfuse::hal::fourcc('Z', 'Z', 'Z', 'Z');
  EXPECT_EQ(V4l2Stream::open(path_, r, &error), nullptr);
  std::printf("unknown fourcc: %s\n", error.c_str());
  EXPECT_TRUE(has(error, path_)) << error;
  EXPECT_TRUE(has(error, "ZZZZ")) << error;
  EXPECT_TRUE(has(error, "offers")) << error;
  EXPECT_TRUE(has(error, "YUYV")) << error;
  EXPECT_TRUE(has(error, "GREY")) << error;

  r = stereo_request();
  r.width = 100000;
  r.height = 100000;
  error.clear();
  EXPECT_EQ(V4l2Stream::open(path_, r, &error), nullptr);
  std::printf("absurd size: %s\n", error.c_str());
  EXPECT_TRUE(has(error, "100000x100000")) << error;
  EXPECT_TRUE(has(error, "offers")) << error;

  // The HDMI input's rate is its timings' (30 fps here): 60 is refused.
  r = stereo_request();
  r.fps = 60;
  error.clear();
  EXPECT_EQ(V4l2Stream::open(path_, r, &error), nullptr);
  std::printf("rate: %s\n", error.c_str());
  EXPECT_TRUE(has(error, "60 fps")) << error;
  EXPECT_TRUE(has(error, "gave 30 fps")) << error;
}

TEST_F(Vivid0, WebcamInputRefusesTheStereoSizeListingItsSizes) {
  {
    RawNode node(path_);
    ASSERT_TRUE(node.ok()) << node.error();
    ASSERT_TRUE(node.select_input("Webcam")) << node.error();
  }
  std::string error;
  EXPECT_EQ(V4l2Stream::open(path_, stereo_request(), &error), nullptr);
  std::printf("webcam input: %s\n", error.c_str());
  // vivid snaps to its nearest discrete size, which the backend refuses.
  EXPECT_TRUE(has(error, "gave YUYV 1280x720")) << error;
  EXPECT_TRUE(has(error, "320x180")) << error;
  EXPECT_TRUE(has(error, "3840x2160")) << error;

  // One of its own sizes and rates is fine.
  VideoRequest r = stereo_request();
  r.width = 640;
  r.height = 480;
  r.fps = 25;
  error.clear();
  auto s = V4l2Stream::open(path_, r, &error);
  ASSERT_NE(s, nullptr) << error;
  EXPECT_EQ(s->format().fps_numerator, 25u * s->format().fps_denominator);
}

// The second instance, so that its disconnect leaves the first alone.
class Vivid1 : public VividTest {
 protected:
  void SetUp() override { use_instance("vivid-001-vid-cap"); }
};

TEST_F(Vivid1, DisconnectIsReportedAsClosedAndReopenRecoversOnceEveryHandleIsClosed) {
  auto s = open_stereo();
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->start(), HalStatus::kOk) << s->last_error();
  for (int i = 0; i < 3; ++i) {
    VideoFrame f;
    ASSERT_NO_FATAL_FAILURE(dequeue_ok(*s, &f));
    ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  }

  // "Unplug" through a handle of our own, kept open: vivid reconnects only
  // once the last handle on the instance is closed.
  RawNode control(path_);
  ASSERT_TRUE(control.ok()) << control.error();
  const std::uint32_t disconnect = control.find_control("Disconnect");
  ASSERT_NE(disconnect, 0u) << control.error();
  ASSERT_TRUE(control.press(disconnect)) << control.error();

  VideoFrame f;
  ASSERT_EQ(s->dequeue(kFrameWait, &f), HalStatus::kClosed) << s->last_error();
  EXPECT_EQ(s->stats().lost, 1);
  EXPECT_TRUE(has(s->last_error(), path_)) << s->last_error();
  EXPECT_TRUE(has(s->last_error(), "went away")) << s->last_error();
  // Still gone, counted once.
  EXPECT_EQ(s->dequeue(kFrameWait, &f), HalStatus::kClosed);
  EXPECT_EQ(s->stats().lost, 1);

  // While anyone holds the instance open its nodes stay unregistered:
  // open(2) fails with ENODEV though /dev still lists the node.
  EXPECT_EQ(access(path_.c_str(), F_OK), 0) << path_ << " vanished from /dev";
  EXPECT_EQ(s->reopen(), HalStatus::kClosed) << s->last_error();
  EXPECT_EQ(s->stats().reopen_failures, 1);
  EXPECT_EQ(s->stats().reopens, 0);
  EXPECT_TRUE(has(s->last_error(), path_)) << s->last_error();
  EXPECT_TRUE(has(s->last_error(), std::strerror(ENODEV))) << s->last_error();
  std::printf("reopen while disconnected: %s\n", s->last_error());
  std::string error;
  EXPECT_EQ(V4l2Stream::open(path_, stereo_request(), &error), nullptr);
  EXPECT_TRUE(has(error, "went away")) << error;

  // The last handle closes (the stream's went in reopen): vivid "replugs".
  control.close();
  ASSERT_EQ(s->reopen(), HalStatus::kOk) << s->last_error();
  EXPECT_EQ(s->stats().reopens, 1);
  EXPECT_EQ(s->stats().lost, 1);
  EXPECT_EQ(s->format().width, kStereoWidth);
  TimeNs last_stamp = 0;
  for (int i = 0; i < 3; ++i) {
    ASSERT_NO_FATAL_FAILURE(dequeue_ok(*s, &f));
    EXPECT_GT(f.stamp, last_stamp);
    last_stamp = f.stamp;
    ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  }
}

}  // namespace
