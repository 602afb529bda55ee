#include "hal/linux/v4l2_stream.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "hal/linux/errno_text.hpp"

namespace rtfuse::hal {
namespace {

int sys_open(const char* path, int flags) { return ::open(path, flags); }
int sys_close(int fd) { return ::close(fd); }
// ::ioctl is variadic, so its address does not fit the table.
int sys_ioctl(int fd, unsigned long request, void* arg) { return ::ioctl(fd, request, arg); }
void* sys_mmap(void* addr, std::size_t length, int prot, int flags, int fd, off_t offset) {
  return ::mmap(addr, length, prot, flags, fd, offset);
}
int sys_munmap(void* addr, std::size_t length) { return ::munmap(addr, length); }
int sys_poll(pollfd* fds, nfds_t nfds, int timeout_ms) { return ::poll(fds, nfds, timeout_ms); }
TimeNs sys_now() { return monotonic_now_ns(); }

const V4l2Syscalls kSystem{&sys_open, &sys_close, &sys_ioctl, &sys_mmap, &sys_munmap, &sys_poll, &sys_now};

// Bounds for enumerations: a driver answers EINVAL past the end, but a buggy
// one must not keep open() looping.
constexpr std::uint32_t kMaxEnum = 64;

// Retries an ioctl interrupted by a signal (only at open; the per-frame
// calls are non-blocking or preceded by poll).
int xioctl(const V4l2Syscalls& sys, int fd, unsigned long request, void* arg) {
  int rc;
  do {
    rc = sys.ioctl(fd, request, arg);
  } while (rc < 0 && errno == EINTR);
  return rc;
}

std::string cstr(const __u8* s, std::size_t n) {
  std::size_t len = 0;
  while (len < n && s[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(s), len);
}

// Frames per second of the interval num/den seconds: "30", "12.5". UVC
// intervals in 100 ns units (333333/10000000) read "30" too.
std::string rate_text(std::uint32_t num, std::uint32_t den) {
  if (num == 0) return "?";
  if (den % num == 0) return std::to_string(den / num);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", static_cast<double>(den) / num);
  std::string t = buf;
  while (t.back() == '0') t.pop_back();
  if (t.back() == '.') t.pop_back();
  return t;
}

std::string size_text(std::uint32_t w, std::uint32_t h) { return std::to_string(w) + "x" + std::to_string(h); }

std::string format_text(std::uint32_t pixel_format, int w, int h) {
  return V4l2Stream::fourcc_text(pixel_format) + " " +
         size_text(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
}

// The interval num/den is within 1 % of 1/fps. Drivers do not all give
// 1/fps exactly: UVC keeps intervals in 100 ns units (1/30 is 333333), and
// reduces them to a fraction that need not be 1/30.
bool rate_matches(int fps, std::uint32_t num, std::uint32_t den) {
  if (num == 0 || den == 0) return false;
  const std::int64_t asked = static_cast<std::int64_t>(fps) * num;
  const std::int64_t diff = static_cast<std::int64_t>(den) - asked;
  return (diff < 0 ? -diff : diff) * 100 <= asked;
}

// What a device is, from its capabilities, for the "not a capture device" message.
const char* device_kind(std::uint32_t caps) {
  if (caps & V4L2_CAP_META_CAPTURE) {
    return "a metadata capture node (UVC cameras add one beside the image node)";
  }
  if (caps & (V4L2_CAP_VIDEO_M2M | V4L2_CAP_VIDEO_M2M_MPLANE)) return "a memory-to-memory device (codec or converter)";
  if (caps & (V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_VIDEO_OUTPUT_MPLANE)) return "a video output device";
  if (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) {
    return "a multi-planar video capture device (this backend does single-planar capture)";
  }
  if (caps & (V4L2_CAP_VBI_CAPTURE | V4L2_CAP_SLICED_VBI_CAPTURE)) return "a VBI capture device";
  if (caps & (V4L2_CAP_SDR_CAPTURE | V4L2_CAP_SDR_OUTPUT)) return "a software-defined radio device";
  if (caps & (V4L2_CAP_RADIO | V4L2_CAP_TUNER | V4L2_CAP_MODULATOR)) return "a radio device";
  if (caps & V4L2_CAP_TOUCH) return "a touch sensor device";
  return "a V4L2 device without video capture";
}

std::string fix_for_open_errno(int err, const std::string& path) {
  switch (err) {
    case EBUSY: return "; another program is using it (find it with fuser -v " + path + ")";
    case ENODEV:
    case ENXIO: return "; the device went away (unplugged?); list video devices with v4l2-ctl --list-devices";
    default: return "";
  }
}

}  // namespace

const V4l2Syscalls& system_v4l2_syscalls() noexcept { return kSystem; }

// --- descriptions ---------------------------------------------------------------

std::string V4l2Stream::fourcc_text(std::uint32_t fourcc) {
  std::string s;
  // Bit 31 marks the big-endian variant of a format; it is not a character.
  const std::uint32_t code = fourcc & ~(1u << 31);
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xffu);
    s += (c >= 0x20 && c < 0x7f) ? c : '?';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  if (fourcc & (1u << 31)) s += "-BE";
  return s;
}

std::string V4l2Stream::describe_open_failure(const std::string& path, int err) {
  std::string msg = "cannot open video device " + path + ": " + ErrnoText(err).text;
  switch (err) {
    case ENOENT:
      msg += "; is the camera plugged in and its driver loaded (uvcvideo for USB cameras)? list video devices with "
             "v4l2-ctl --list-devices";
      break;
    case EACCES:
    case EPERM:
      msg += "; add the user to group video (usermod -aG video $USER, then log in again) or add a udev rule giving "
             "that group access to " +
             path;
      break;
    default: msg += fix_for_open_errno(err, path); break;
  }
  return msg;
}

std::string V4l2Stream::describe_rates(int fd, const V4l2Syscalls& sys, std::uint32_t pixel_format, int width,
                                       int height) {
  struct Rate {
    std::uint32_t num, den;  // interval num/den seconds
  };
  std::vector<Rate> rates;
  std::string range;
  for (std::uint32_t i = 0; i < kMaxEnum; ++i) {
    v4l2_frmivalenum iv{};
    iv.index = i;
    iv.pixel_format = pixel_format;
    iv.width = static_cast<std::uint32_t>(width);
    iv.height = static_cast<std::uint32_t>(height);
    if (xioctl(sys, fd, VIDIOC_ENUM_FRAMEINTERVALS, &iv) < 0) break;
    if (iv.type == V4L2_FRMIVAL_TYPE_DISCRETE) {
      rates.push_back({iv.discrete.numerator, iv.discrete.denominator});
      continue;
    }
    // Stepwise or continuous: one entry; the longest interval is the lowest rate.
    range = rate_text(iv.stepwise.max.numerator, iv.stepwise.max.denominator) + ".." +
            rate_text(iv.stepwise.min.numerator, iv.stepwise.min.denominator);
    break;
  }
  if (!range.empty()) return range;
  // Lowest rate first, whatever order the driver lists them in (UVC: as the
  // camera's descriptors do, usually fastest first).
  std::sort(rates.begin(), rates.end(), [](const Rate& a, const Rate& b) {
    return static_cast<std::uint64_t>(a.den) * b.num < static_cast<std::uint64_t>(b.den) * a.num;
  });
  std::string out;
  std::string last;
  for (const Rate& r : rates) {
    const std::string t = rate_text(r.num, r.den);
    if (t == last) continue;
    if (!out.empty()) out += "/";
    out += t;
    last = t;
  }
  return out;
}

std::string V4l2Stream::describe_offered(int fd, const V4l2Syscalls& sys, std::uint32_t detail_format) {
  std::vector<std::uint32_t> formats;
  for (std::uint32_t i = 0; i < kMaxEnum; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(sys, fd, VIDIOC_ENUM_FMT, &d) < 0) break;
    formats.push_back(d.pixelformat);
  }
  const auto detailed = [&](std::uint32_t f) {
    std::string s = fourcc_text(f);
    std::string sizes;
    for (std::uint32_t i = 0; i < kMaxEnum; ++i) {
      v4l2_frmsizeenum fs{};
      fs.index = i;
      fs.pixel_format = f;
      if (xioctl(sys, fd, VIDIOC_ENUM_FRAMESIZES, &fs) < 0) break;
      if (!sizes.empty()) sizes += ", ";
      if (fs.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        sizes += size_text(fs.discrete.width, fs.discrete.height);
        const std::string rates = describe_rates(fd, sys, f, static_cast<int>(fs.discrete.width),
                                                 static_cast<int>(fs.discrete.height));
        if (!rates.empty()) sizes += " @" + rates;
        continue;
      }
      sizes += size_text(fs.stepwise.min_width, fs.stepwise.min_height) + ".." +
               size_text(fs.stepwise.max_width, fs.stepwise.max_height);
      if (fs.type == V4L2_FRMSIZE_TYPE_STEPWISE) {
        sizes += "/" + size_text(fs.stepwise.step_width, fs.stepwise.step_height);
      }
      break;
    }
    if (!sizes.empty()) s += " " + sizes;
    return s;
  };

  // A detail format the device lacks: everything in detail, to choose from.
  if (std::find(formats.begin(), formats.end(), detail_format) == formats.end()) detail_format = 0;
  std::string out;
  std::string others;
  if (detail_format != 0) out = detailed(detail_format);
  for (std::uint32_t f : formats) {
    if (detail_format == 0) {
      if (!out.empty()) out += "; ";
      out += detailed(f);
    } else if (f != detail_format) {
      if (!others.empty()) others += ", ";
      others += fourcc_text(f);
    }
  }
  if (!others.empty()) out += (out.empty() ? "" : "; also ") + others;
  return out;
}

// --- open -----------------------------------------------------------------------

std::unique_ptr<V4l2Stream> V4l2Stream::open(const std::string& path, const VideoRequest& req, std::string* error) {
  return open(path, req, error, nullptr, system_v4l2_syscalls());
}

std::unique_ptr<V4l2Stream> V4l2Stream::open(const std::string& path, const VideoRequest& req, std::string* error,
                                             V4l2OpenFailure* failure, const V4l2Syscalls& sys) {
  std::unique_ptr<V4l2Stream> s(new V4l2Stream(path, req, sys));
  V4l2OpenFailure local;
  if (failure == nullptr) failure = &local;
  *failure = V4l2OpenFailure{};
  std::string msg;
  if (!s->open_device(&msg, failure)) {
    if (error) *error = std::move(msg);
    return nullptr;
  }
  return s;
}

V4l2Stream::V4l2Stream(std::string path, const VideoRequest& req, const V4l2Syscalls& sys)
    : path_(std::move(path)), request_(req), sys_(sys) {}

V4l2Stream::~V4l2Stream() { close_device(); }

bool V4l2Stream::open_device(std::string* error, V4l2OpenFailure* failure) {
  const VideoRequest& req = request_;
  const auto fail = [&](V4l2OpenFailure::Stage stage, int err, std::string msg) {
    failure->stage = stage;
    failure->err = err;
    *error = std::move(msg);
    close_device();
    return false;
  };
  const std::string asked = format_text(req.pixel_format, req.width, req.height);

  if (req.width <= 0 || req.height <= 0 || req.fps < 0) {
    return fail(V4l2OpenFailure::Stage::kRequest, 0,
                path_ + ": invalid request " + asked + " @" + std::to_string(req.fps) +
                    " fps (width and height must be positive, fps 0 or more)");
  }
  if (req.buffers < 2 || req.buffers > kMaxVideoBuffers) {
    return fail(V4l2OpenFailure::Stage::kRequest, 0,
                path_ + ": invalid request of " + std::to_string(req.buffers) + " buffers (2.." +
                    std::to_string(kMaxVideoBuffers) + ")");
  }

  // Non-blocking: DQBUF must never sleep in the kernel; poll() is the wait.
  const int fd = sys_.open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return fail(V4l2OpenFailure::Stage::kOpen, err, describe_open_failure(path_, err));
  }
  fd_ = fd;

  v4l2_capability cap{};
  if (xioctl(sys_, fd, VIDIOC_QUERYCAP, &cap) < 0) {
    const int err = errno;
    if (err == ENODEV) {
      return fail(V4l2OpenFailure::Stage::kOpen, err,
                  path_ + ": VIDIOC_QUERYCAP failed: " + ErrnoText(err).text + fix_for_open_errno(err, path_));
    }
    return fail(V4l2OpenFailure::Stage::kCapabilities, err,
                path_ + " is not a V4L2 device (VIDIOC_QUERYCAP failed: " + ErrnoText(err).text +
                    "); pass a video capture node such as /dev/video0 (list them with v4l2-ctl --list-devices)");
  }
  failure->card = cstr(cap.card, sizeof cap.card);
  failure->driver = cstr(cap.driver, sizeof cap.driver);
  failure->bus_info = cstr(cap.bus_info, sizeof cap.bus_info);
  const std::string who = path_ + " (\"" + failure->card + "\", driver " + failure->driver + ", " +
                          failure->bus_info + ")";
  // capabilities describes the whole physical device (all its nodes);
  // device_caps, when present, this node alone: a UVC camera's metadata node
  // would otherwise look like a capture node.
  const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
    return fail(V4l2OpenFailure::Stage::kCapabilities, 0,
                who + " is " + device_kind(caps) +
                    ", not a video capture device; pick the camera's capture node from v4l2-ctl --list-devices "
                    "(usually the first listed under the camera)");
  }
  if ((caps & V4L2_CAP_STREAMING) == 0) {
    return fail(V4l2OpenFailure::Stage::kCapabilities, 0,
                who + " is a video capture device without streaming I/O (read() only), which this backend does not "
                      "do; use a driver that supports mmap streaming");
  }

  // --- format ---
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(req.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(req.height);
  fmt.fmt.pix.pixelformat = req.pixel_format;
  fmt.fmt.pix.field = V4L2_FIELD_ANY;
  if (xioctl(sys_, fd, VIDIOC_S_FMT, &fmt) < 0) {
    const int err = errno;
    failure->offered = describe_offered(fd, sys_, req.pixel_format);
    std::string msg = who + ": VIDIOC_S_FMT " + asked + " failed: " + ErrnoText(err).text;
    if (err == EBUSY) {
      msg += "; another program is streaming from it (find it with fuser -v " + path_ + ")";
    } else if (!failure->offered.empty()) {
      msg += "; it offers " + failure->offered;
    }
    return fail(V4l2OpenFailure::Stage::kFormat, err, std::move(msg));
  }
  VideoFormat f;
  f.pixel_format = fmt.fmt.pix.pixelformat;
  f.width = static_cast<int>(fmt.fmt.pix.width);
  f.height = static_cast<int>(fmt.fmt.pix.height);
  f.bytes_per_line = static_cast<int>(fmt.fmt.pix.bytesperline);
  f.image_size = fmt.fmt.pix.sizeimage;
  failure->given = f;
  // Drivers answer S_FMT with the nearest format they have instead of an
  // error (a UVC camera on USB 2 drops its large sizes this way).
  if (f.pixel_format != req.pixel_format || f.width != req.width || f.height != req.height) {
    failure->offered = describe_offered(fd, sys_, req.pixel_format);
    return fail(V4l2OpenFailure::Stage::kFormat, 0,
                who + ": asked for " + asked + ", the device gave " + format_text(f.pixel_format, f.width, f.height) +
                    "; it offers " + (failure->offered.empty() ? std::string("nothing it can enumerate")
                                                               : failure->offered));
  }

  // --- frame rate ---
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (req.fps > 0) {
    parm.parm.capture.timeperframe.numerator = 1;
    parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(req.fps);
    const std::string rate_asked = std::to_string(req.fps) + " fps at " + asked;
    if (xioctl(sys_, fd, VIDIOC_S_PARM, &parm) < 0) {
      const int err = errno;
      failure->offered = describe_rates(fd, sys_, req.pixel_format, req.width, req.height);
      return fail(V4l2OpenFailure::Stage::kFrameRate, err,
                  who + ": VIDIOC_S_PARM " + rate_asked + " failed: " + ErrnoText(err).text +
                      (failure->offered.empty() ? std::string("; ask for fps 0 to keep the device's rate")
                                                : "; that size offers @" + failure->offered));
    }
    const v4l2_fract& tpf = parm.parm.capture.timeperframe;
    f.fps_numerator = tpf.denominator;
    f.fps_denominator = tpf.numerator;
    failure->given = f;
    if ((parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) == 0) {
      return fail(V4l2OpenFailure::Stage::kFrameRate, 0,
                  who + ": asked for " + rate_asked +
                      ", but the driver cannot set the frame rate (no V4L2_CAP_TIMEPERFRAME); ask for fps 0 to "
                      "take its rate");
    }
    if (!rate_matches(req.fps, tpf.numerator, tpf.denominator)) {
      failure->offered = describe_rates(fd, sys_, req.pixel_format, req.width, req.height);
      return fail(V4l2OpenFailure::Stage::kFrameRate, 0,
                  who + ": asked for " + rate_asked + ", the device gave " + rate_text(tpf.numerator, tpf.denominator) +
                      " fps; that size offers " +
                      (failure->offered.empty() ? std::string("rates it cannot enumerate") : "@" + failure->offered));
    }
  } else if (xioctl(sys_, fd, VIDIOC_G_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator != 0) {
    f.fps_numerator = parm.parm.capture.timeperframe.denominator;
    f.fps_denominator = parm.parm.capture.timeperframe.numerator;
  }

  // --- buffers ---
  v4l2_requestbuffers rb{};
  rb.count = static_cast<std::uint32_t>(req.buffers);
  rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  rb.memory = V4L2_MEMORY_MMAP;
  if (xioctl(sys_, fd, VIDIOC_REQBUFS, &rb) < 0) {
    const int err = errno;
    return fail(V4l2OpenFailure::Stage::kBuffers, err,
                who + ": VIDIOC_REQBUFS " + std::to_string(req.buffers) + " mmap buffers failed: " +
                    ErrnoText(err).text +
                    (err == EBUSY ? "; another program is streaming from it (find it with fuser -v " + path_ + ")"
                                  : std::string()));
  }
  allocated_ = rb.count > 0;
  // A driver may give fewer (memory) or more (its minimum) than asked.
  if (rb.count < 2 || rb.count > static_cast<std::uint32_t>(kMaxVideoBuffers)) {
    return fail(V4l2OpenFailure::Stage::kBuffers, 0,
                who + ": asked for " + std::to_string(req.buffers) + " mmap buffers, the driver gave " +
                    std::to_string(rb.count) + "; streaming needs 2.." + std::to_string(kMaxVideoBuffers));
  }
  for (std::uint32_t i = 0; i < rb.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(sys_, fd, VIDIOC_QUERYBUF, &b) < 0) {
      const int err = errno;
      return fail(V4l2OpenFailure::Stage::kBuffers, err,
                  who + ": VIDIOC_QUERYBUF " + std::to_string(i) + " failed: " + ErrnoText(err).text);
    }
    void* p = sys_.mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, static_cast<off_t>(b.m.offset));
    if (p == MAP_FAILED) {
      const int err = errno;
      return fail(V4l2OpenFailure::Stage::kBuffers, err,
                  who + ": mmap of buffer " + std::to_string(i) + " (" + std::to_string(b.length) +
                      " bytes) failed: " + ErrnoText(err).text);
    }
    buffers_[i] = Buffer{p, b.length, false};
    nbuffers_ = static_cast<int>(i) + 1;
  }
  f.buffers = nbuffers_;
  format_ = f;
  failure->stage = V4l2OpenFailure::Stage::kNone;
  return true;
}

void V4l2Stream::close_device() noexcept {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    sys_.ioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  for (int i = 0; i < nbuffers_; ++i) {
    if (buffers_[i].data != nullptr) sys_.munmap(buffers_[i].data, buffers_[i].length);
    buffers_[i] = Buffer{};
  }
  nbuffers_ = 0;
  if (fd_ >= 0 && allocated_) {
    v4l2_requestbuffers rb{};
    rb.count = 0;
    rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    rb.memory = V4L2_MEMORY_MMAP;
    sys_.ioctl(fd_, VIDIOC_REQBUFS, &rb);  // fails with ENODEV after an unplug; close frees them then
  }
  allocated_ = false;
  if (fd_ >= 0) sys_.close(fd_);
  fd_ = -1;
}

// --- streaming ------------------------------------------------------------------

void V4l2Stream::set_error(const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(last_error_, sizeof last_error_, fmt, ap);
  va_end(ap);
}

HalStatus V4l2Stream::device_gone(const char* op) noexcept {
  if (!closed_) ++stats_.lost;
  closed_ = true;
  set_error("%s: %s: %s; the device went away (unplugged?); reopen() when it is back", path_.c_str(), op,
            ErrnoText(ENODEV).text);
  return HalStatus::kClosed;
}

HalStatus V4l2Stream::start() noexcept {
  if (closed_ || fd_ < 0) {
    set_error("%s: start: the device is closed; reopen() it", path_.c_str());
    return HalStatus::kClosed;
  }
  if (streaming_) return HalStatus::kOk;
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  for (int i = 0; i < nbuffers_; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = static_cast<std::uint32_t>(i);
    if (sys_.ioctl(fd_, VIDIOC_QBUF, &b) < 0) {
      const int err = errno;
      sys_.ioctl(fd_, VIDIOC_STREAMOFF, &type);  // takes back the buffers queued so far
      if (err == ENODEV) return device_gone("VIDIOC_QBUF");
      set_error("%s: VIDIOC_QBUF buffer %d failed: %s", path_.c_str(), i, ErrnoText(err).text);
      return HalStatus::kIoError;
    }
    buffers_[i].lent = false;
  }
  if (sys_.ioctl(fd_, VIDIOC_STREAMON, &type) < 0) {
    const int err = errno;
    sys_.ioctl(fd_, VIDIOC_STREAMOFF, &type);
    if (err == ENODEV) return device_gone("VIDIOC_STREAMON");
    // uvcvideo answers ENOSPC when the USB bus cannot reserve the isochronous
    // bandwidth the format and rate need.
    set_error(err == ENOSPC ? "%s: VIDIOC_STREAMON failed: %s; not enough USB bandwidth for this size and rate "
                              "(another camera on the same controller, or a USB 2 port): lower the rate or size, "
                              "or give the camera its own USB 3 port"
                            : "%s: VIDIOC_STREAMON failed: %s",
              path_.c_str(), ErrnoText(err).text);
    return HalStatus::kIoError;
  }
  streaming_ = true;
  // STREAMON restarts the driver's sequence count at 0.
  sequence_.reset();
  return HalStatus::kOk;
}

void V4l2Stream::stop() noexcept {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (sys_.ioctl(fd_, VIDIOC_STREAMOFF, &type) < 0) {
      const int err = errno;
      if (err == ENODEV) {
        device_gone("VIDIOC_STREAMOFF");
      } else {
        set_error("%s: VIDIOC_STREAMOFF failed: %s", path_.c_str(), ErrnoText(err).text);
      }
    }
  }
  streaming_ = false;
  for (int i = 0; i < nbuffers_; ++i) buffers_[i].lent = false;
}

HalStatus V4l2Stream::dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept {
  if (closed_ || fd_ < 0) {
    set_error("%s: dequeue: the device is closed; reopen() it", path_.c_str());
    return HalStatus::kClosed;
  }
  if (!streaming_) {
    set_error("%s: dequeue while not streaming; call start() first", path_.c_str());
    return HalStatus::kIoError;
  }
  pollfd p{fd_, POLLIN, 0};
  const TimeNs begin = sys_.now();
  const TimeNs wait = timeout_ns > 0 ? timeout_ns : 0;
  const TimeNs deadline = wait > INT64_MAX - begin ? INT64_MAX : begin + wait;
  for (;;) {
    TimeNs left = deadline - sys_.now();
    if (left < 0) left = 0;
    // Round up: a frame due in 0.4 ms must not be given up on at once.
    const TimeNs ms = (left + 999'999) / 1'000'000;
    p.revents = 0;
    const int rc = sys_.poll(&p, 1, ms > INT_MAX ? INT_MAX : static_cast<int>(ms));
    if (rc > 0) break;
    if (rc == 0) {
      ++stats_.timeouts;
      return HalStatus::kTimeout;
    }
    const int err = errno;
    if (err == EINTR) continue;  // a signal: wait out the rest
    set_error("%s: poll failed: %s", path_.c_str(), ErrnoText(err).text);
    return HalStatus::kIoError;
  }
  if (p.revents & POLLNVAL) {
    set_error("%s: poll: the file descriptor is not open (POLLNVAL)", path_.c_str());
    return HalStatus::kIoError;
  }

  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (sys_.ioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    const int err = errno;
    // An unplugged device (UVC disconnect, vivid's "Disconnect" control)
    // polls as POLLERR | POLLHUP and every ioctl then fails with ENODEV.
    if (err == ENODEV) return device_gone("VIDIOC_DQBUF");
    if (err == EAGAIN) {
      if ((p.revents & (POLLERR | POLLHUP)) == 0) {
        ++stats_.timeouts;  // woken but nothing done: as if the wait ran out
        return HalStatus::kTimeout;
      }
      // vb2 polls POLLERR when nothing is queued for it to fill.
      set_error("%s: poll reported an error but VIDIOC_DQBUF has no buffer (none queued?)", path_.c_str());
      return HalStatus::kIoError;
    }
    set_error(err == EIO ? "%s: VIDIOC_DQBUF failed: %s; the driver stopped the stream after a fatal error: stop() "
                           "and start() again"
                         : "%s: VIDIOC_DQBUF failed: %s",
              path_.c_str(), ErrnoText(err).text);
    return HalStatus::kIoError;
  }
  if (b.index >= static_cast<std::uint32_t>(nbuffers_)) {
    set_error("%s: VIDIOC_DQBUF gave buffer index %u, only %d are mapped", path_.c_str(), b.index, nbuffers_);
    return HalStatus::kIoError;
  }
  Buffer& buf = buffers_[b.index];
  buf.lent = true;

  frame->index = static_cast<int>(b.index);
  frame->data = static_cast<const std::uint8_t*>(buf.data);
  frame->length = static_cast<std::uint32_t>(buf.length);
  frame->bytes_used = b.bytesused;
  frame->sequence = b.sequence;
  frame->corrupted = (b.flags & V4L2_BUF_FLAG_ERROR) != 0;
  if (b.bytesused > buf.length) {
    // Never reported by a sane driver; a consumer reading bytes_used bytes
    // must not run off the mapping.
    frame->bytes_used = frame->length;
    frame->corrupted = true;
  }
  // The kernel's stamp is the capture time only on CLOCK_MONOTONIC. Other
  // timestamp types (UNKNOWN: old drivers stamping gettimeofday(), i.e.
  // CLOCK_REALTIME, which NTP steps; COPY: a memory-to-memory device copying
  // the stamp of its input) are on another clock: fused with monotonic
  // sensor times they would be off by decades or jump. The dequeue time is
  // late by the delivery latency but on the right clock.
  if ((b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    frame->stamp =
        static_cast<TimeNs>(b.timestamp.tv_sec) * kNsPerSec + static_cast<TimeNs>(b.timestamp.tv_usec) * kNsPerUs;
  } else {
    frame->stamp = sys_.now();
  }

  ++stats_.frames;
  const std::uint32_t gap = sequence_.observe(b.sequence);
  if (gap > 0) {
    stats_.dropped += gap;
    ++stats_.sequence_gaps;
  }
  if (frame->corrupted) ++stats_.corrupted;
  return HalStatus::kOk;
}

HalStatus V4l2Stream::release(int index) noexcept {
  if (index < 0 || index >= nbuffers_ || !buffers_[index].lent) {
    set_error("%s: release of buffer %d, which is not lent", path_.c_str(), index);
    return HalStatus::kIoError;
  }
  if (closed_ || fd_ < 0) {
    buffers_[index].lent = false;
    return HalStatus::kClosed;
  }
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = static_cast<std::uint32_t>(index);
  if (sys_.ioctl(fd_, VIDIOC_QBUF, &b) < 0) {
    const int err = errno;
    if (err == ENODEV) {
      buffers_[index].lent = false;
      return device_gone("VIDIOC_QBUF");
    }
    // Still lent: the caller may try again; the device is one buffer short until then.
    set_error("%s: VIDIOC_QBUF buffer %d failed: %s", path_.c_str(), index, ErrnoText(err).text);
    return HalStatus::kIoError;
  }
  buffers_[index].lent = false;
  return HalStatus::kOk;
}

HalStatus V4l2Stream::reopen() noexcept {
  close_device();
  closed_ = false;
  // Allocates (the message, the mapping bookkeeping is fixed): reopen runs
  // only after the device went away, never on a healthy stream.
  std::string msg;
  reopen_failure_ = V4l2OpenFailure{};
  if (!open_device(&msg, &reopen_failure_)) {
    closed_ = true;
    ++stats_.reopen_failures;
    set_error("%s", msg.c_str());
    const int err = reopen_failure_.err;
    const bool absent = reopen_failure_.stage == V4l2OpenFailure::Stage::kOpen &&
                        (err == ENOENT || err == ENODEV || err == ENXIO);
    return absent ? HalStatus::kClosed : HalStatus::kIoError;
  }
  const std::int64_t lost = stats_.lost;
  const HalStatus s = start();
  if (s != HalStatus::kOk) {
    stats_.lost = lost;  // the device was not up yet: not a second loss
    reopen_failure_.stage = V4l2OpenFailure::Stage::kStart;
    close_device();
    closed_ = true;
    ++stats_.reopen_failures;
    return s;
  }
  ++stats_.reopens;
  return HalStatus::kOk;
}

}  // namespace rtfuse::hal
