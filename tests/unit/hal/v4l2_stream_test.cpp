// V4l2Stream: the real open failures this machine can produce (its kernel
// has no V4L2), and everything else against an emulated V4L2 capture device
// behind the syscall table: a ZED-like UVC camera that clamps sizes on USB 2,
// picks the nearest rate, and hands out vb2-style buffers.
#include "hal/linux/v4l2_stream.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "support/alloc_counter.hpp"

namespace rtfuse::hal {
namespace v4l2_stream_test {

// The emulated device. Plain globals: the seam is a table of function
// pointers, and the allocation test runs through it.
namespace fake {
constexpr int kFd = 42;
constexpr const char* kPath = "/dev/video0";
constexpr std::uint32_t kBufLen = 4096;  // far below a real frame: only the backend's bookkeeping is tested
constexpr int kMaxBufs = 16;

struct Size {
  std::uint32_t w, h;
  int nrates;
  std::uint32_t rates[4];  // fps, fastest first as UVC descriptors list them
};
// A ZED 2i: side-by-side YUYV, its four modes.
const Size kZedSizes[] = {
    {4416, 1242, 1, {15}},
    {3840, 1080, 2, {30, 15}},
    {2560, 720, 3, {60, 30, 15}},
    {1344, 376, 4, {100, 60, 30, 15}},
};
const Size kMjpgSizes[] = {{1280, 720, 1, {30}}};
// MJPG intervals as a UVC camera gives them: in 100 ns units, not reduced.
constexpr std::uint32_t kUvcUnits = 10'000'000;

struct Done {
  int index;
  std::uint32_t sequence, flags, bytesused;
  TimeNs stamp;
};

struct Device {
  // configuration
  bool present = true;  // open: ENOENT otherwise
  bool gone = false;    // unplugged while open: ENODEV everywhere, POLLERR
  std::uint32_t capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_DEVICE_CAPS;
  std::uint32_t device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  bool usb2 = false;  // only the smallest mode (a ZED on a USB 2 port)
  bool with_mjpg = true;
  bool with_grey_stepwise = false;
  int s_fmt_errno = 0;
  int s_parm_errno = 0;
  bool timeperframe = true;  // V4L2_CAP_TIMEPERFRAME
  bool uvc_units = false;    // S_PARM answers in 100 ns units, unreduced
  int reqbufs_give = -1;     // -1: what was asked
  int streamon_errno = 0;
  bool spurious_pollin = false;  // poll says POLLIN, DQBUF has nothing
  int poll_eintr = 0;            // this many polls fail with EINTR first
  // state
  int opens = 0, closes = 0, open_flags = 0;
  bool is_open = false;
  bool streaming = false;
  std::uint32_t fourcc = V4L2_PIX_FMT_YUYV, w = 1344, h = 376, fps = 30;
  int nbufs = 0;
  bool queued[kMaxBufs] = {};
  int qfifo[kMaxBufs] = {};
  int nq = 0;
  Done done[kMaxBufs] = {};
  int ndone = 0;
  int mapped = 0, unmapped = 0;
  int qbufs = 0, dqbufs = 0, streamons = 0, streamoffs = 0, reqbufs_zero = 0;
  int polls = 0, last_poll_ms = -2, dropped_by_device = 0;
  TimeNs now = 5'000'000'000;  // the fake CLOCK_MONOTONIC
  std::uint8_t memory[kMaxBufs][kBufLen] = {};
};
Device dev;

void reset() { dev = Device{}; }

int nsizes(std::uint32_t fourcc) {
  if (fourcc == V4L2_PIX_FMT_YUYV) return dev.usb2 ? 1 : 4;
  if (fourcc == V4L2_PIX_FMT_MJPEG) return 1;
  return 0;
}
const Size& size_at(std::uint32_t fourcc, int i) {
  if (fourcc == V4L2_PIX_FMT_MJPEG) return kMjpgSizes[i];
  return dev.usb2 ? kZedSizes[3] : kZedSizes[i];
}
std::uint32_t format_at(std::uint32_t index, bool* ok) {
  std::uint32_t f[3];
  std::uint32_t n = 0;
  f[n++] = V4L2_PIX_FMT_YUYV;
  if (dev.with_mjpg) f[n++] = V4L2_PIX_FMT_MJPEG;
  if (dev.with_grey_stepwise) f[n++] = V4L2_PIX_FMT_GREY;
  *ok = index < n;
  return *ok ? f[index] : 0;
}
bool offered(std::uint32_t fourcc) {
  bool ok = true;
  for (std::uint32_t i = 0; ok; ++i) {
    if (format_at(i, &ok) == fourcc && ok) return true;
  }
  return false;
}
const Size* find_size(std::uint32_t fourcc, std::uint32_t w, std::uint32_t h) {
  for (int i = 0; i < nsizes(fourcc); ++i) {
    if (size_at(fourcc, i).w == w && size_at(fourcc, i).h == h) return &size_at(fourcc, i);
  }
  return nullptr;
}

int fail(int e) {
  errno = e;
  return -1;
}

// Hands a frame to the oldest queued buffer, as the driver's interrupt would;
// false if none is queued (the device drops the frame).
bool deliver(std::uint32_t sequence, std::uint32_t flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC,
             std::uint32_t bytesused = kBufLen, TimeNs stamp = 0) {
  if (dev.nq == 0) {
    ++dev.dropped_by_device;
    return false;
  }
  const int i = dev.qfifo[0];
  for (int k = 1; k < dev.nq; ++k) dev.qfifo[k - 1] = dev.qfifo[k];
  --dev.nq;
  dev.queued[i] = false;
  std::memset(dev.memory[i], static_cast<int>(sequence & 0xff), kBufLen);
  dev.done[dev.ndone++] = Done{i, sequence, flags, bytesused, stamp};
  return true;
}

int open(const char* path, int flags) {
  if (std::strcmp(path, kPath) != 0 || !dev.present) return fail(ENOENT);
  if (dev.gone) return fail(ENODEV);  // vivid after "Disconnect": the node stays, open fails
  ++dev.opens;
  dev.open_flags = flags;
  dev.is_open = true;
  return kFd;
}

int close(int fd) {
  if (fd != kFd) return fail(EBADF);
  ++dev.closes;
  dev.is_open = false;
  dev.streaming = false;
  dev.nbufs = 0;  // the kernel frees the queue with the last file handle
  for (bool& q : dev.queued) q = false;
  dev.nq = 0;
  dev.ndone = 0;
  return 0;
}

void* mmap(void*, std::size_t length, int, int flags, int fd, off_t offset) {
  if (fd != kFd || dev.gone) {
    errno = ENODEV;
    return MAP_FAILED;
  }
  const int i = static_cast<int>(offset / kBufLen);
  if (length != kBufLen || offset % kBufLen != 0 || i >= dev.nbufs || (flags & MAP_SHARED) == 0) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++dev.mapped;
  return dev.memory[i];
}

int munmap(void*, std::size_t) {
  ++dev.unmapped;
  return 0;
}

int poll(pollfd* fds, nfds_t n, int timeout_ms) {
  ++dev.polls;
  dev.last_poll_ms = timeout_ms;
  if (n != 1 || fds[0].fd != kFd) return fail(EINVAL);
  if (dev.poll_eintr > 0) {
    --dev.poll_eintr;
    return fail(EINTR);
  }
  if (dev.gone) {
    fds[0].revents = POLLERR | POLLHUP | POLLPRI;  // v4l2_poll of an unregistered node
    return 1;
  }
  if (!dev.streaming) {
    fds[0].revents = POLLERR;
    return 1;
  }
  if (dev.ndone > 0 || dev.spurious_pollin) {
    fds[0].revents = POLLIN | POLLRDNORM;
    return 1;
  }
  fds[0].revents = 0;
  return 0;
}

TimeNs now() { return dev.now; }

int ioctl(int fd, unsigned long request, void* arg) {
  if (fd != kFd || !dev.is_open) return fail(EBADF);
  if (dev.gone) return fail(ENODEV);
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* c = static_cast<v4l2_capability*>(arg);
      std::memset(c, 0, sizeof *c);
      std::strcpy(reinterpret_cast<char*>(c->driver), "uvcvideo");
      std::strcpy(reinterpret_cast<char*>(c->card), "ZED 2i");
      std::strcpy(reinterpret_cast<char*>(c->bus_info), "usb-3610000.xhci-2");
      c->capabilities = dev.capabilities;
      c->device_caps = dev.device_caps;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto* d = static_cast<v4l2_fmtdesc*>(arg);
      bool ok = false;
      const std::uint32_t f = format_at(d->index, &ok);
      if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || !ok) return fail(EINVAL);
      d->pixelformat = f;
      return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* s = static_cast<v4l2_frmsizeenum*>(arg);
      if (s->pixel_format == V4L2_PIX_FMT_GREY && dev.with_grey_stepwise) {
        if (s->index != 0) return fail(EINVAL);
        s->type = V4L2_FRMSIZE_TYPE_STEPWISE;
        s->stepwise = v4l2_frmsize_stepwise{16, 640, 2, 16, 480, 2};
        return 0;
      }
      if (static_cast<int>(s->index) >= nsizes(s->pixel_format)) return fail(EINVAL);
      s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
      s->discrete.width = size_at(s->pixel_format, static_cast<int>(s->index)).w;
      s->discrete.height = size_at(s->pixel_format, static_cast<int>(s->index)).h;
      return 0;
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
      auto* iv = static_cast<v4l2_frmivalenum*>(arg);
      if (iv->pixel_format == V4L2_PIX_FMT_GREY && dev.with_grey_stepwise) {
        if (iv->index != 0) return fail(EINVAL);
        iv->type = V4L2_FRMIVAL_TYPE_CONTINUOUS;
        iv->stepwise.min = v4l2_fract{1, 60};
        iv->stepwise.max = v4l2_fract{1, 1};
        iv->stepwise.step = v4l2_fract{1, 1};
        return 0;
      }
      const Size* s = find_size(iv->pixel_format, iv->width, iv->height);
      if (s == nullptr || static_cast<int>(iv->index) >= s->nrates) return fail(EINVAL);
      iv->type = V4L2_FRMIVAL_TYPE_DISCRETE;
      iv->discrete = v4l2_fract{1, s->rates[iv->index]};
      if (iv->pixel_format == V4L2_PIX_FMT_MJPEG) iv->discrete = v4l2_fract{kUvcUnits / 30 + 1, kUvcUnits};
      return 0;
    }
    case VIDIOC_S_FMT: {
      if (dev.s_fmt_errno) return fail(dev.s_fmt_errno);
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      v4l2_pix_format& p = f->fmt.pix;
      // Like uvcvideo: an unknown format becomes the first, the size the
      // nearest offered one.
      if (!offered(p.pixelformat) || p.pixelformat == V4L2_PIX_FMT_GREY) p.pixelformat = V4L2_PIX_FMT_YUYV;
      const Size* best = &size_at(p.pixelformat, 0);
      long best_d = -1;
      for (int i = 0; i < nsizes(p.pixelformat); ++i) {
        const Size& s = size_at(p.pixelformat, i);
        const long d = std::labs(static_cast<long>(s.w) - static_cast<long>(p.width)) +
                       std::labs(static_cast<long>(s.h) - static_cast<long>(p.height));
        if (best_d < 0 || d < best_d) {
          best = &s;
          best_d = d;
        }
      }
      p.width = best->w;
      p.height = best->h;
      p.field = V4L2_FIELD_NONE;
      p.bytesperline = p.pixelformat == V4L2_PIX_FMT_YUYV ? 2 * p.width : 0;
      p.sizeimage = 2 * p.width * p.height;
      dev.fourcc = p.pixelformat;
      dev.w = p.width;
      dev.h = p.height;
      dev.fps = best->rates[best->nrates - 1];
      return 0;
    }
    case VIDIOC_S_PARM:
    case VIDIOC_G_PARM: {
      auto* parm = static_cast<v4l2_streamparm*>(arg);
      if (parm->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_PARM) {
        if (dev.s_parm_errno) return fail(dev.s_parm_errno);
        const v4l2_fract t = parm->parm.capture.timeperframe;
        const Size* s = find_size(dev.fourcc, dev.w, dev.h);
        if (dev.timeperframe && s != nullptr && t.numerator != 0) {
          // The nearest offered rate, as uvcvideo picks it.
          const std::uint32_t want = t.denominator / t.numerator;
          std::uint32_t best = s->rates[0];
          for (int i = 0; i < s->nrates; ++i) {
            const auto dist = [&](std::uint32_t r) { return r > want ? r - want : want - r; };
            if (dist(s->rates[i]) < dist(best)) best = s->rates[i];
          }
          dev.fps = best;
        }
      }
      std::memset(&parm->parm, 0, sizeof parm->parm);
      parm->parm.capture.capability = dev.timeperframe ? V4L2_CAP_TIMEPERFRAME : 0;
      parm->parm.capture.timeperframe = v4l2_fract{1, dev.fps};
      if (dev.uvc_units) parm->parm.capture.timeperframe = v4l2_fract{kUvcUnits / dev.fps, kUvcUnits};
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* rb = static_cast<v4l2_requestbuffers*>(arg);
      if (rb->memory != V4L2_MEMORY_MMAP || rb->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (dev.streaming) return fail(EBUSY);
      if (rb->count == 0) {
        ++dev.reqbufs_zero;
        dev.nbufs = 0;
        return 0;
      }
      rb->count = dev.reqbufs_give >= 0 ? static_cast<std::uint32_t>(dev.reqbufs_give) : rb->count;
      if (rb->count > kMaxBufs) rb->count = kMaxBufs;
      dev.nbufs = static_cast<int>(rb->count);
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (static_cast<int>(b->index) >= dev.nbufs) return fail(EINVAL);
      b->length = kBufLen;
      b->m.offset = b->index * kBufLen;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      const int i = static_cast<int>(b->index);
      if (i >= dev.nbufs || dev.queued[i] || b->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
      for (int k = 0; k < dev.ndone; ++k) {
        if (dev.done[k].index == i) return fail(EINVAL);
      }
      ++dev.qbufs;
      dev.queued[i] = true;
      dev.qfifo[dev.nq++] = i;
      return 0;
    }
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (!dev.streaming) return fail(EINVAL);
      if (dev.ndone == 0) return fail(EAGAIN);
      const Done d = dev.done[0];
      for (int k = 1; k < dev.ndone; ++k) dev.done[k - 1] = dev.done[k];
      --dev.ndone;
      ++dev.dqbufs;
      b->index = static_cast<std::uint32_t>(d.index);
      b->sequence = d.sequence;
      b->flags = d.flags;
      b->bytesused = d.bytesused;
      b->length = kBufLen;
      b->field = V4L2_FIELD_NONE;
      b->timestamp.tv_sec = d.stamp / kNsPerSec;
      b->timestamp.tv_usec = (d.stamp % kNsPerSec) / kNsPerUs;
      return 0;
    }
    case VIDIOC_STREAMON:
      if (dev.streamon_errno) return fail(dev.streamon_errno);
      ++dev.streamons;
      dev.streaming = true;
      return 0;
    case VIDIOC_STREAMOFF:
      ++dev.streamoffs;
      dev.streaming = false;
      for (int i = 0; i < kMaxBufs; ++i) dev.queued[i] = false;
      dev.nq = 0;
      dev.ndone = 0;
      return 0;
    default: return fail(ENOTTY);
  }
}

const V4l2Syscalls kTable{&fake::open, &fake::close, &fake::ioctl, &fake::mmap, &fake::munmap, &fake::poll,
                          &fake::now};
}  // namespace fake

VideoRequest zed_request(int w = 1344, int h = 376, int fps = 30, int buffers = 4) {
  VideoRequest r;
  r.pixel_format = kFourccYuyv;
  r.width = w;
  r.height = h;
  r.fps = fps;
  r.buffers = buffers;
  return r;
}

class V4l2StreamTest : public ::testing::Test {
 protected:
  void SetUp() override { fake::reset(); }
  std::unique_ptr<V4l2Stream> open(const VideoRequest& req = zed_request()) {
    return V4l2Stream::open(fake::kPath, req, &error_, &failure_, fake::kTable);
  }
  std::unique_ptr<V4l2Stream> open_started(const VideoRequest& req = zed_request()) {
    auto s = open(req);
    EXPECT_NE(s, nullptr) << error_;
    if (s) {
      EXPECT_EQ(s->start(), HalStatus::kOk) << s->last_error();
    }
    return s;
  }
  // Nothing is held after a failed open.
  void expect_released() {
    EXPECT_EQ(fake::dev.opens, fake::dev.closes);
    EXPECT_EQ(fake::dev.mapped, fake::dev.unmapped);
    EXPECT_EQ(fake::dev.nbufs, 0);
  }
  std::string error_;
  V4l2OpenFailure failure_;
};

// --- open on this machine -------------------------------------------------------

TEST(V4l2StreamOpen, MissingNodeNamesPathAndListCommand) {
  if (::access("/dev/video99", F_OK) == 0) GTEST_SKIP() << "/dev/video99 exists on this machine";
  std::string error;
  EXPECT_EQ(V4l2Stream::open("/dev/video99", zed_request(), &error), nullptr);
  EXPECT_EQ(error,
            "cannot open video device /dev/video99: No such file or directory; is the camera plugged in and its "
            "driver loaded (uvcvideo for USB cameras)? list video devices with v4l2-ctl --list-devices");
}

TEST(V4l2StreamOpen, FileThatIsNotV4l2IsRejectedAtQuerycap) {
  std::string error;
  V4l2OpenFailure failure;
  EXPECT_EQ(V4l2Stream::open("/dev/null", zed_request(), &error, &failure), nullptr);
  // The kernel answers ENOTTY; qemu-user, which does not translate the V4L2
  // ioctls, may answer ENOSYS first. Either errno text is passed on.
  const std::string head = "/dev/null is not a V4L2 device (VIDIOC_QUERYCAP failed: ";
  const std::string tail =
      "); pass a video capture node such as /dev/video0 (list them with v4l2-ctl --list-devices)";
  EXPECT_TRUE(error == head + std::strerror(ENOTTY) + tail || error == head + std::strerror(ENOSYS) + tail) << error;
  EXPECT_EQ(failure.stage, V4l2OpenFailure::Stage::kCapabilities);
}

TEST(V4l2StreamOpen, PermissionDeniedNamesGroupVideo) {
  EXPECT_EQ(V4l2Stream::describe_open_failure("/dev/video0", EACCES),
            "cannot open video device /dev/video0: Permission denied; add the user to group video (usermod -aG video "
            "$USER, then log in again) or add a udev rule giving that group access to /dev/video0");
}

TEST(V4l2StreamOpen, FourccText) {
  EXPECT_EQ(V4l2Stream::fourcc_text(kFourccYuyv), "YUYV");
  EXPECT_EQ(V4l2Stream::fourcc_text(fourcc('Y', '1', '0', ' ')), "Y10");
  EXPECT_EQ(V4l2Stream::fourcc_text(fourcc('Y', '1', '6', ' ') | (1u << 31)), "Y16-BE");
  EXPECT_EQ(V4l2Stream::fourcc_text(0x01020304), "????");
}

// --- capabilities ---------------------------------------------------------------

TEST_F(V4l2StreamTest, OpensCaptureNodeNonBlockingAndNegotiates) {
  auto s = open();
  ASSERT_NE(s, nullptr) << error_;
  EXPECT_EQ(fake::dev.open_flags, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  const VideoFormat& f = s->format();
  EXPECT_EQ(f.pixel_format, kFourccYuyv);
  EXPECT_EQ(f.width, 1344);
  EXPECT_EQ(f.height, 376);
  EXPECT_EQ(f.bytes_per_line, 2688);
  EXPECT_EQ(f.image_size, 2u * 1344 * 376);
  EXPECT_EQ(f.fps_numerator, 30u);
  EXPECT_EQ(f.fps_denominator, 1u);
  EXPECT_EQ(f.buffers, 4);
  EXPECT_EQ(fake::dev.mapped, 4);
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kNone);
  EXPECT_FALSE(s->streaming());
}

TEST_F(V4l2StreamTest, OutputOnlyDeviceIsRejected) {
  fake::dev.capabilities = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING | V4L2_CAP_DEVICE_CAPS;
  fake::dev.device_caps = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
  EXPECT_EQ(open(), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2) is a video output device, not a video "
            "capture device; pick the camera's capture node from v4l2-ctl --list-devices (usually the first listed "
            "under the camera)");
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kCapabilities);
  EXPECT_EQ(failure_.card, "ZED 2i");
  expect_released();
}

TEST_F(V4l2StreamTest, MetadataNodeIsJudgedByDeviceCapsNotTheWholeDevice) {
  // A UVC camera's second node: the device as a whole captures video, this node only metadata.
  fake::dev.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING |
                           V4L2_CAP_DEVICE_CAPS;
  fake::dev.device_caps = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;
  EXPECT_EQ(open(), nullptr);
  EXPECT_NE(error_.find("is a metadata capture node (UVC cameras add one beside the image node), not a video "
                        "capture device"),
            std::string::npos)
      << error_;
  expect_released();
}

TEST_F(V4l2StreamTest, OldDriverWithoutDeviceCapsUsesCapabilities) {
  fake::dev.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  fake::dev.device_caps = 0;  // not valid without V4L2_CAP_DEVICE_CAPS
  EXPECT_NE(open(), nullptr) << error_;
}

TEST_F(V4l2StreamTest, CaptureWithoutStreamingIsRejected) {
  fake::dev.device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  EXPECT_EQ(open(), nullptr);
  EXPECT_NE(error_.find("is a video capture device without streaming I/O (read() only)"), std::string::npos)
      << error_;
}

TEST_F(V4l2StreamTest, MultiplanarOnlyDeviceIsNamedAsSuch) {
  fake::dev.device_caps = V4L2_CAP_VIDEO_CAPTURE_MPLANE | V4L2_CAP_STREAMING;
  EXPECT_EQ(open(), nullptr);
  EXPECT_NE(error_.find("is a multi-planar video capture device (this backend does single-planar capture)"),
            std::string::npos)
      << error_;
}

TEST_F(V4l2StreamTest, InvalidRequestFailsBeforeTouchingTheDevice) {
  EXPECT_EQ(open(zed_request(1344, 376, 30, 9)), nullptr);
  EXPECT_EQ(error_, "/dev/video0: invalid request of 9 buffers (2..8)");
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kRequest);
  EXPECT_EQ(open(zed_request(0, 376)), nullptr);
  EXPECT_EQ(fake::dev.opens, 0);
}

// --- format ---------------------------------------------------------------------

TEST_F(V4l2StreamTest, Usb2ClampedSizeFailsWithWhatWasAskedGivenAndOffered) {
  fake::dev.usb2 = true;
  EXPECT_EQ(open(zed_request(2560, 720)), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): asked for YUYV 2560x720, the device gave "
            "YUYV 1344x376; it offers YUYV 1344x376 @15/30/60/100; also MJPG");
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kFormat);
  EXPECT_EQ(failure_.err, 0);
  EXPECT_EQ(failure_.given.width, 1344);
  EXPECT_EQ(failure_.given.height, 376);
  EXPECT_EQ(failure_.offered, "YUYV 1344x376 @15/30/60/100; also MJPG");
  EXPECT_EQ(failure_.bus_info, "usb-3610000.xhci-2");
  expect_released();
}

TEST_F(V4l2StreamTest, UnofferedPixelFormatListsEveryFormatInDetail) {
  VideoRequest r = zed_request();
  r.pixel_format = kFourccGrey;
  EXPECT_EQ(open(r), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): asked for GREY 1344x376, the device gave "
            "YUYV 1344x376; it offers YUYV 4416x1242 @15, 3840x1080 @15/30, 2560x720 @15/30/60, 1344x376 "
            "@15/30/60/100; MJPG 1280x720 @30");
}

TEST_F(V4l2StreamTest, DescribeOfferedStepwiseSizesAndContinuousRates) {
  fake::dev.with_mjpg = false;
  fake::dev.with_grey_stepwise = true;
  fake::dev.usb2 = true;
  fake::dev.is_open = true;
  EXPECT_EQ(V4l2Stream::describe_offered(fake::kFd, fake::kTable),
            "YUYV 1344x376 @15/30/60/100; GREY 16x16..640x480/2x2");
  EXPECT_EQ(V4l2Stream::describe_rates(fake::kFd, fake::kTable, V4L2_PIX_FMT_GREY, 320, 240), "1..60");
  EXPECT_EQ(V4l2Stream::describe_rates(fake::kFd, fake::kTable, V4L2_PIX_FMT_YUYV, 2560, 720), "");
}

TEST_F(V4l2StreamTest, SetFormatBusyNamesTheOtherProgram) {
  fake::dev.s_fmt_errno = EBUSY;
  EXPECT_EQ(open(), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): VIDIOC_S_FMT YUYV 1344x376 failed: Device "
            "or resource busy; another program is streaming from it (find it with fuser -v /dev/video0)");
  EXPECT_EQ(failure_.err, EBUSY);
  expect_released();
}

// --- frame rate -----------------------------------------------------------------

TEST_F(V4l2StreamTest, RateNotOfferedForTheSizeFailsListingThatSizesRates) {
  EXPECT_EQ(open(zed_request(2560, 720, 100)), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): asked for 100 fps at YUYV 2560x720, the "
            "device gave 60 fps; that size offers @15/30/60");
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kFrameRate);
  EXPECT_EQ(failure_.given.fps_numerator, 60u);
  EXPECT_EQ(failure_.offered, "15/30/60");
  expect_released();
}

TEST_F(V4l2StreamTest, RateIn100nsUnitsMatchesItsWholeNumber) {
  fake::dev.uvc_units = true;
  auto s = open(zed_request(1344, 376, 30));
  ASSERT_NE(s, nullptr) << error_;
  EXPECT_EQ(s->format().fps_numerator, 10'000'000u);
  EXPECT_EQ(s->format().fps_denominator, 333'333u);
  fake::reset();
  fake::dev.uvc_units = true;
  EXPECT_EQ(open(zed_request(1344, 376, 45)), nullptr);  // nearest offered: 60
  EXPECT_NE(error_.find("asked for 45 fps at YUYV 1344x376, the device gave 60 fps"), std::string::npos) << error_;
}

TEST_F(V4l2StreamTest, SetParmErrorFails) {
  fake::dev.s_parm_errno = ENOTTY;
  EXPECT_EQ(open(), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): VIDIOC_S_PARM 30 fps at YUYV 1344x376 "
            "failed: Inappropriate ioctl for device; that size offers @15/30/60/100");
}

TEST_F(V4l2StreamTest, DriverThatCannotSetTheRateFails) {
  fake::dev.timeperframe = false;
  EXPECT_EQ(open(), nullptr);
  EXPECT_NE(error_.find("the driver cannot set the frame rate (no V4L2_CAP_TIMEPERFRAME); ask for fps 0"),
            std::string::npos)
      << error_;
}

TEST_F(V4l2StreamTest, FpsZeroKeepsAndReportsTheDevicesRate) {
  auto s = open(zed_request(2560, 720, 0));
  ASSERT_NE(s, nullptr) << error_;
  EXPECT_EQ(s->format().fps_numerator, 15u);  // the fake's rate after S_FMT: the slowest
  EXPECT_EQ(s->format().fps_denominator, 1u);
}

// --- buffers --------------------------------------------------------------------

TEST_F(V4l2StreamTest, FewerBuffersThanAskedAreAccepted) {
  fake::dev.reqbufs_give = 3;
  auto s = open(zed_request(1344, 376, 30, 6));
  ASSERT_NE(s, nullptr) << error_;
  EXPECT_EQ(s->format().buffers, 3);
  EXPECT_EQ(fake::dev.mapped, 3);
}

TEST_F(V4l2StreamTest, OneBufferIsTooFewAndIsFreedAgain) {
  fake::dev.reqbufs_give = 1;
  EXPECT_EQ(open(), nullptr);
  EXPECT_EQ(error_,
            "/dev/video0 (\"ZED 2i\", driver uvcvideo, usb-3610000.xhci-2): asked for 4 mmap buffers, the driver gave "
            "1; streaming needs 2..8");
  EXPECT_EQ(failure_.stage, V4l2OpenFailure::Stage::kBuffers);
  EXPECT_EQ(fake::dev.reqbufs_zero, 1);
  expect_released();
}

TEST_F(V4l2StreamTest, MoreBuffersThanTheFixedCapacityFail) {
  fake::dev.reqbufs_give = kMaxVideoBuffers + 1;
  EXPECT_EQ(open(), nullptr);
  EXPECT_NE(error_.find("the driver gave 9; streaming needs 2..8"), std::string::npos) << error_;
  expect_released();
}

// --- streaming ------------------------------------------------------------------

TEST_F(V4l2StreamTest, StartQueuesEveryBufferAndStreamsOn) {
  auto s = open_started();
  EXPECT_EQ(fake::dev.qbufs, 4);
  EXPECT_EQ(fake::dev.streamons, 1);
  EXPECT_TRUE(s->streaming());
  EXPECT_EQ(s->start(), HalStatus::kOk);  // already streaming: nothing again
  EXPECT_EQ(fake::dev.qbufs, 4);
}

TEST_F(V4l2StreamTest, DequeueLendsTheBufferWithKernelStampAndReleaseRequeues) {
  auto s = open_started();
  ASSERT_TRUE(fake::deliver(0, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, 1000, 7'123'456'000));
  VideoFrame f;
  ASSERT_EQ(s->dequeue(10'000'000, &f), HalStatus::kOk) << s->last_error();
  EXPECT_EQ(f.index, 0);
  EXPECT_EQ(f.data, fake::dev.memory[0]);
  EXPECT_EQ(f.length, fake::kBufLen);
  EXPECT_EQ(f.bytes_used, 1000u);
  EXPECT_EQ(f.stamp, 7'123'456'000);
  EXPECT_EQ(f.sequence, 0u);
  EXPECT_FALSE(f.corrupted);
  EXPECT_EQ(s->stats().frames, 1);
  EXPECT_EQ(fake::dev.last_poll_ms, 10);
  EXPECT_EQ(s->release(f.index), HalStatus::kOk);
  EXPECT_EQ(fake::dev.qbufs, 5);
  EXPECT_TRUE(fake::dev.queued[0]);
  EXPECT_EQ(s->release(f.index), HalStatus::kIoError);  // no double QBUF
  EXPECT_STREQ(s->last_error(), "/dev/video0: release of buffer 0, which is not lent");
}

TEST_F(V4l2StreamTest, SequenceGapsCountDrops) {
  auto s = open_started();
  VideoFrame f;
  for (std::uint32_t seq : {0u, 1u, 4u, 5u, 9u}) {
    ASSERT_TRUE(fake::deliver(seq));
    ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
    EXPECT_EQ(f.sequence, seq);
    ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  }
  EXPECT_EQ(s->stats().frames, 5);
  EXPECT_EQ(s->stats().dropped, 2 + 3);
  EXPECT_EQ(s->stats().sequence_gaps, 2);
}

TEST_F(V4l2StreamTest, ErrorFlagMarksTheFrameCorrupted) {
  auto s = open_started();
  ASSERT_TRUE(fake::deliver(0, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_ERROR, 17));
  VideoFrame f;
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_TRUE(f.corrupted);
  EXPECT_EQ(f.bytes_used, 17u);
  EXPECT_EQ(s->stats().corrupted, 1);
}

TEST_F(V4l2StreamTest, WrongBytesUsedIsPassedThroughButNeverPastTheBuffer) {
  auto s = open_started();
  VideoFrame f;
  ASSERT_TRUE(fake::deliver(0, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, 123));
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(f.bytes_used, 123u);  // short frame: the consumer compares with image_size
  EXPECT_FALSE(f.corrupted);
  ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  ASSERT_TRUE(fake::deliver(1, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, fake::kBufLen + 1));
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(f.bytes_used, fake::kBufLen);
  EXPECT_TRUE(f.corrupted);
}

TEST_F(V4l2StreamTest, NonMonotonicTimestampsAreReplacedByTheDequeueTime) {
  auto s = open_started();
  // An old driver's gettimeofday() stamp: CLOCK_REALTIME, decades off.
  ASSERT_TRUE(fake::deliver(0, V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN, fake::kBufLen, 1'700'000'000 * kNsPerSec));
  fake::dev.now = 9'000'000'000;
  VideoFrame f;
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(f.stamp, 9'000'000'000);
  ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  ASSERT_TRUE(fake::deliver(1, V4L2_BUF_FLAG_TIMESTAMP_COPY, fake::kBufLen, 42 * kNsPerSec));
  fake::dev.now = 9'100'000'000;
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(f.stamp, 9'100'000'000);
}

TEST_F(V4l2StreamTest, NothingWithinTheTimeoutIsATimeout) {
  auto s = open_started();
  VideoFrame f;
  EXPECT_EQ(s->dequeue(1'500'000, &f), HalStatus::kTimeout);
  EXPECT_EQ(fake::dev.last_poll_ms, 2);  // rounded up, never 0 for a wait asked for
  EXPECT_EQ(s->dequeue(0, &f), HalStatus::kTimeout);
  EXPECT_EQ(fake::dev.last_poll_ms, 0);
  EXPECT_EQ(s->stats().timeouts, 2);
  EXPECT_EQ(s->stats().frames, 0);
}

TEST_F(V4l2StreamTest, EagainAfterPollIsATimeout) {
  auto s = open_started();
  fake::dev.spurious_pollin = true;
  VideoFrame f;
  EXPECT_EQ(s->dequeue(5'000'000, &f), HalStatus::kTimeout);
  EXPECT_EQ(s->stats().timeouts, 1);
}

TEST_F(V4l2StreamTest, InterruptedPollWaitsAgain) {
  auto s = open_started();
  fake::dev.poll_eintr = 2;
  ASSERT_TRUE(fake::deliver(0));
  VideoFrame f;
  EXPECT_EQ(s->dequeue(5'000'000, &f), HalStatus::kOk);
  EXPECT_EQ(fake::dev.polls, 3);
}

TEST_F(V4l2StreamTest, DequeueBeforeStartIsAnError) {
  auto s = open();
  ASSERT_NE(s, nullptr);
  VideoFrame f;
  EXPECT_EQ(s->dequeue(0, &f), HalStatus::kIoError);
  EXPECT_STREQ(s->last_error(), "/dev/video0: dequeue while not streaming; call start() first");
  EXPECT_EQ(fake::dev.polls, 0);
}

TEST_F(V4l2StreamTest, StopReturnsLentBuffersAndStartQueuesAllAgain) {
  auto s = open_started();
  ASSERT_TRUE(fake::deliver(0));
  VideoFrame f;
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  s->stop();
  EXPECT_EQ(fake::dev.streamoffs, 1);
  EXPECT_FALSE(s->streaming());
  EXPECT_EQ(s->release(f.index), HalStatus::kIoError);  // back with the stream already
  ASSERT_EQ(s->start(), HalStatus::kOk);
  EXPECT_EQ(fake::dev.nq, 4);
  // The driver counts from 0 again after STREAMON: not a gap.
  ASSERT_TRUE(fake::deliver(0));
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(s->stats().dropped, 0);
}

TEST_F(V4l2StreamTest, StreamonWithoutUsbBandwidthSaysSo) {
  fake::dev.streamon_errno = ENOSPC;
  auto s = open();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->start(), HalStatus::kIoError);
  EXPECT_NE(std::string(s->last_error()).find("VIDIOC_STREAMON failed: No space left on device; not enough USB "
                                              "bandwidth"),
            std::string::npos)
      << s->last_error();
  EXPECT_FALSE(s->streaming());
  EXPECT_EQ(fake::dev.nq, 0);  // the queued buffers were taken back
}

TEST_F(V4l2StreamTest, UnplugMidStreamIsClosedOnceThenReopenFailsUntilTheDeviceIsBack) {
  auto s = open_started();
  ASSERT_TRUE(fake::deliver(0));
  VideoFrame lent;
  ASSERT_EQ(s->dequeue(0, &lent), HalStatus::kOk);
  ASSERT_TRUE(fake::deliver(1));

  fake::dev.gone = true;  // POLLERR | POLLHUP, then ENODEV from DQBUF
  VideoFrame f;
  EXPECT_EQ(s->dequeue(10'000'000, &f), HalStatus::kClosed);
  EXPECT_EQ(s->stats().lost, 1);
  EXPECT_STREQ(s->last_error(),
               "/dev/video0: VIDIOC_DQBUF: No such device; the device went away (unplugged?); reopen() when it is "
               "back");
  EXPECT_EQ(s->dequeue(0, &f), HalStatus::kClosed);
  EXPECT_EQ(s->stats().lost, 1);  // one loss, however often asked
  EXPECT_EQ(s->release(lent.index), HalStatus::kClosed);

  EXPECT_EQ(s->reopen(), HalStatus::kClosed);
  EXPECT_EQ(s->stats().reopen_failures, 1);
  EXPECT_EQ(fake::dev.closes, 1);  // the dead fd is let go: the driver can free the device
  EXPECT_EQ(fake::dev.unmapped, 4);
  EXPECT_EQ(s->reopen_failure().stage, V4l2OpenFailure::Stage::kOpen);
  EXPECT_STREQ(s->last_error(),
               "cannot open video device /dev/video0: No such device; the device went away (unplugged?); list video "
               "devices with v4l2-ctl --list-devices");
  EXPECT_EQ(s->dequeue(0, &f), HalStatus::kClosed);

  fake::dev.gone = false;
  ASSERT_EQ(s->reopen(), HalStatus::kOk) << s->last_error();
  EXPECT_EQ(s->stats().reopens, 1);
  EXPECT_EQ(fake::dev.opens, 2);
  EXPECT_TRUE(s->streaming());
  EXPECT_EQ(fake::dev.nq, 4);
  EXPECT_EQ(s->format().width, 1344);
  // Sequence restarts with the new stream: no gap counted.
  ASSERT_TRUE(fake::deliver(0, V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, 10));
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  EXPECT_EQ(f.bytes_used, 10u);
  EXPECT_EQ(s->stats().dropped, 0);
  EXPECT_EQ(s->stats().lost, 1);
}

TEST_F(V4l2StreamTest, UnplugSeenByReleaseIsClosedToo) {
  auto s = open_started();
  ASSERT_TRUE(fake::deliver(0));
  VideoFrame f;
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  fake::dev.gone = true;
  EXPECT_EQ(s->release(f.index), HalStatus::kClosed);
  EXPECT_EQ(s->stats().lost, 1);
  EXPECT_EQ(s->dequeue(0, &f), HalStatus::kClosed);
  EXPECT_EQ(s->stats().lost, 1);
}

TEST_F(V4l2StreamTest, DestructorStreamsOffUnmapsFreesAndCloses) {
  auto s = open_started();
  s.reset();
  EXPECT_EQ(fake::dev.streamoffs, 1);
  EXPECT_EQ(fake::dev.unmapped, 4);
  EXPECT_EQ(fake::dev.reqbufs_zero, 1);
  EXPECT_EQ(fake::dev.closes, 1);
}

TEST_F(V4l2StreamTest, DequeueAndReleaseDoNotAllocate) {
  auto s = open_started();
  VideoFrame f;
  // Warm up once outside the scope (first use of any lazy state).
  ASSERT_TRUE(fake::deliver(0));
  ASSERT_EQ(s->dequeue(0, &f), HalStatus::kOk);
  ASSERT_EQ(s->release(f.index), HalStatus::kOk);
  std::size_t allocations = 0;
  {
    test::AllocScope scope;
    for (std::uint32_t seq = 1; seq < 200; ++seq) {
      // Three frames lost at 50, 100 and 150; every 7th flagged; stamps of both kinds.
      fake::deliver(seq + 3 * (seq / 50), (seq % 7 == 0 ? V4L2_BUF_FLAG_ERROR : 0u) |
                                              (seq % 3 == 0 ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : 0u));
      if (s->dequeue(1'000'000, &f) != HalStatus::kOk) break;
      if (s->release(f.index) != HalStatus::kOk) break;
    }
    (void)s->dequeue(0, &f);      // timeout
    (void)s->release(7);          // error text
    fake::dev.gone = true;
    (void)s->dequeue(0, &f);      // unplug text
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(s->stats().frames, 200);
  EXPECT_EQ(s->stats().corrupted, 28);
  EXPECT_EQ(s->stats().dropped, 9);
  EXPECT_EQ(s->stats().lost, 1);
}

}  // namespace v4l2_stream_test
}  // namespace rtfuse::hal
