#pragma once
// VideoStream over a Linux V4L2 capture node (/dev/videoN), mmap streaming,
// raw ioctls (no libv4l: its format conversion would copy every frame).
//
// open() negotiates and allocates; start() queues every buffer and turns the
// stream on; dequeue()/release() are the per-frame path (poll + DQBUF, QBUF)
// and never allocate. A device that refuses the exact format, size or rate
// asked for is an error at open, with the list of what it does offer: a
// silently smaller image or slower rate would break calibration and timing
// further down.
//
// Every system call goes through a V4l2Syscalls table so tests can put an
// emulated kernel device behind it.
#include <poll.h>
#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "hal/video_stream.hpp"

namespace rtfuse::hal {

struct V4l2Syscalls {
  int (*open)(const char* path, int flags);
  int (*close)(int fd);
  int (*ioctl)(int fd, unsigned long request, void* arg);
  void* (*mmap)(void* addr, std::size_t length, int prot, int flags, int fd, off_t offset);
  int (*munmap)(void* addr, std::size_t length);
  int (*poll)(pollfd* fds, nfds_t nfds, int timeout_ms);
  // CLOCK_MONOTONIC ns: stamps frames whose kernel timestamp is on another clock.
  TimeNs (*now)();
};

// The real kernel.
const V4l2Syscalls& system_v4l2_syscalls() noexcept;

// Why an open failed, for callers that add their own hint (a ZED on USB 2
// shows up as kFormat: the device offers only the smaller sizes).
struct V4l2OpenFailure {
  enum class Stage : std::uint8_t {
    kNone,
    kRequest,       // the request itself is invalid (size, buffer count)
    kOpen,          // open(2) failed: see err
    kCapabilities,  // not a V4L2 capture node with streaming I/O
    kFormat,        // VIDIOC_S_FMT failed or gave another pixel format or size
    kFrameRate,     // VIDIOC_S_PARM failed or gave another rate
    kBuffers,       // VIDIOC_REQBUFS / VIDIOC_QUERYBUF / mmap
    kStart,         // reopen(): VIDIOC_QBUF / VIDIOC_STREAMON
  };
  Stage stage = Stage::kNone;
  int err = 0;          // errno of the failed call; 0 when the device answered otherwise
  VideoFormat given;    // what the device chose (kFormat, kFrameRate)
  std::string offered;  // describe_offered() of the device (kFormat), or the size's rates (kFrameRate)
  std::string card;     // from VIDIOC_QUERYCAP, when it got that far
  std::string driver;
  std::string bus_info;  // e.g. "usb-0000:00:14.0-2"
};

class V4l2Stream final : public VideoStream {
 public:
  // Opens and negotiates (does not start). On failure returns null and sets
  // *error to a message naming the device, what was asked, what the device
  // gave or offers, the errno text and the likely fix.
  static std::unique_ptr<V4l2Stream> open(const std::string& path, const VideoRequest& req, std::string* error);
  // The same with the failure's details and another syscall table (tests).
  static std::unique_ptr<V4l2Stream> open(const std::string& path, const VideoRequest& req, std::string* error,
                                          V4l2OpenFailure* failure,
                                          const V4l2Syscalls& sys = system_v4l2_syscalls());

  // What an open capture node offers (VIDIOC_ENUM_FMT, _ENUM_FRAMESIZES,
  // _ENUM_FRAMEINTERVALS), one entry per pixel format:
  // "YUYV 1344x376 @15/30/60/100, 2560x720 @15/30/60; MJPG 1280x720 @30".
  // With detail_format set, that format comes first with its sizes and rates
  // and the others by name only ("...; also MJPG, UYVY"): a test device
  // offering forty formats stays readable. (All in detail if the device
  // lacks detail_format.) Fractional rates read "12.5";
  // stepwise sizes "16x16..1920x1080/2x2"; ranges of rates "@1..60". Empty
  // if the device enumerates nothing.
  static std::string describe_offered(int fd, const V4l2Syscalls& sys, std::uint32_t detail_format = 0);
  // The rates one size offers: "15/30/60"; empty if not enumerable.
  static std::string describe_rates(int fd, const V4l2Syscalls& sys, std::uint32_t pixel_format, int width,
                                    int height);
  // "YUYV"; unprintable bytes as '?'.
  static std::string fourcc_text(std::uint32_t fourcc);
  // The start-up message for an open(2) that failed with err.
  static std::string describe_open_failure(const std::string& path, int err);

  ~V4l2Stream() override;
  V4l2Stream(const V4l2Stream&) = delete;
  V4l2Stream& operator=(const V4l2Stream&) = delete;

  const VideoFormat& format() const noexcept override { return format_; }
  HalStatus start() noexcept override;
  void stop() noexcept override;
  HalStatus dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept override;
  HalStatus release(int index) noexcept override;
  // Lent frames do not survive a reopen (their memory is unmapped).
  HalStatus reopen() noexcept override;
  const VideoStreamStats& stats() const noexcept override { return stats_; }
  const char* last_error() const noexcept override { return last_error_; }

  const std::string& path() const noexcept { return path_; }
  const VideoRequest& request() const noexcept { return request_; }
  bool streaming() const noexcept { return streaming_; }
  // Details of the last failed reopen() (stage kNone after a good one).
  const V4l2OpenFailure& reopen_failure() const noexcept { return reopen_failure_; }

 private:
  struct Buffer {
    void* data = nullptr;
    std::size_t length = 0;
    bool lent = false;
  };

  V4l2Stream(std::string path, const VideoRequest& req, const V4l2Syscalls& sys);
  // Opens, negotiates, maps; false with *error / *failure set and nothing held.
  bool open_device(std::string* error, V4l2OpenFailure* failure);
  // STREAMOFF, munmap, REQBUFS 0, close: back to nothing held.
  void close_device() noexcept;
  HalStatus device_gone(const char* op) noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  std::string path_;
  VideoRequest request_;
  V4l2Syscalls sys_;
  int fd_ = -1;
  bool allocated_ = false;  // VIDIOC_REQBUFS gave buffers (freed with a count of 0)
  bool streaming_ = false;
  bool closed_ = false;  // the device went away; only reopen() helps
  VideoFormat format_;
  Buffer buffers_[kMaxVideoBuffers];
  int nbuffers_ = 0;
  SequenceTracker sequence_;
  VideoStreamStats stats_;
  V4l2OpenFailure reopen_failure_;
  // Fixed storage: failures are formatted without allocating in the RT path.
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal
