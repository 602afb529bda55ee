#include "drivers/camera/stereo_camera.hpp"

#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <cstdint>

#include "core/xxh64.hpp"

namespace rtfuse::drivers {

namespace {

constexpr const char* kWho = "zed camera";

// "YUYV"; unprintable bytes as '?' (no allocation: the check also runs after
// a reopen, on the camera thread).
void fourcc_chars(std::uint32_t f, char out[5]) {
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((f >> (8 * i)) & 0xFFu);
    out[i] = (c >= 0x20 && c < 0x7F) ? c : '?';
  }
  out[4] = '\0';
}

}  // namespace

std::uint64_t chain_pair_digest(std::uint64_t previous, const std::uint8_t* left, const std::uint8_t* right,
                                int width, int height, int stride) noexcept {
  Xxh64 h(previous);
  const auto row_bytes = static_cast<std::size_t>(width > 0 ? width : 0);
  const std::uint8_t* const eyes[2] = {left, right};
  for (const std::uint8_t* eye : eyes) {
    for (int y = 0; y < height; ++y) h.update(eye + static_cast<std::ptrdiff_t>(y) * stride, row_bytes);
  }
  return h.digest();
}

const char* to_string(StereoStepOutcome outcome) noexcept {
  switch (outcome) {
    case StereoStepOutcome::kFrame: return "frame";
    case StereoStepOutcome::kTimeout: return "timeout";
    case StereoStepOutcome::kRejected: return "rejected";
    case StereoStepOutcome::kPoolFull: return "pool full";
    case StereoStepOutcome::kLost: return "lost";
    case StereoStepOutcome::kDown: return "down";
    case StereoStepOutcome::kReopened: return "reopened";
    case StereoStepOutcome::kError: return "error";
  }
  return "?";
}

std::unique_ptr<StereoCamera> StereoCamera::create(const StereoCameraConfig& config, hal::VideoStream& stream,
                                                   hal::Clock& clock, FramePool& pool, std::string* error) {
  auto fail = [&](const std::string& msg) {
    if (error) *error = std::string(kWho) + ": " + msg;
    return nullptr;
  };
  CameraMode mode;
  std::string mode_error;
  if (!find_camera_mode(config.resolution, config.fps, &mode, &mode_error)) return fail(mode_error);
  if (config.expected_serial != 0 && config.calibration_serial != config.expected_serial) {
    return fail("the calibration is for serial " + std::to_string(config.calibration_serial) +
                " but the configuration expects camera " + std::to_string(config.expected_serial) +
                ": load SN" + std::to_string(config.expected_serial) + ".conf (calib.stereolabs.com/?SN=" +
                std::to_string(config.expected_serial) + ")");
  }
  if (config.calibration.width != mode.eye_width || config.calibration.height != mode.eye_height) {
    return fail("the calibration is for " + std::to_string(config.calibration.width) + "x" +
                std::to_string(config.calibration.height) + " per eye but mode " + resolution_name(mode.resolution) +
                " is " + std::to_string(mode.eye_width) + "x" + std::to_string(mode.eye_height) +
                ": load the calibration for resolution " + resolution_name(mode.resolution));
  }
  if (pool.width() != mode.eye_width || pool.height() != mode.eye_height) {
    return fail("the frame pool holds " + std::to_string(pool.width()) + "x" + std::to_string(pool.height()) +
                " images but mode " + resolution_name(mode.resolution) + " rectifies to " +
                std::to_string(mode.eye_width) + "x" + std::to_string(mode.eye_height));
  }
  if (config.reopen_backoff_initial_ns <= 0 || config.reopen_backoff_max_ns < config.reopen_backoff_initial_ns) {
    return fail("reopen backoff must be > 0 with max >= initial (initial " +
                std::to_string(config.reopen_backoff_initial_ns) + " ns, max " +
                std::to_string(config.reopen_backoff_max_ns) + " ns)");
  }
  if (config.max_frames_per_step < 1) {
    return fail("max_frames_per_step must be >= 1 (got " + std::to_string(config.max_frames_per_step) + ")");
  }
  StereoRectification rectification;
  std::string rect_error;
  if (!compute_stereo_rectification(config.calibration, &rectification, &rect_error)) {
    return fail("cannot rectify with this calibration: " + rect_error);
  }
  std::unique_ptr<StereoCamera> cam(new StereoCamera(config, mode, stream, clock, pool, rectification));
  if (!cam->format_fits(stream.format())) return fail(cam->stats_.last_error);
  if (cam->rectifier_.width() != mode.eye_width) return fail("the rectifier refused the eye size");
  const hal::HalStatus s = stream.start();
  if (s != hal::HalStatus::kOk) {
    return fail(std::string("cannot start streaming (") + hal::to_string(s) + "): " + stream.last_error());
  }
  cam->refresh_stream_stats();
  return cam;
}

StereoCamera::StereoCamera(const StereoCameraConfig& config, const CameraMode& mode, hal::VideoStream& stream,
                           hal::Clock& clock, FramePool& pool, const StereoRectification& rectification)
    : config_(config),
      mode_(mode),
      stream_(stream),
      clock_(clock),
      pool_(pool),
      rectification_(rectification),
      rectifier_(config.calibration, rectification, stream.format().bytes_per_line),
      backoff_(config.reopen_backoff_initial_ns) {}

void StereoCamera::set_error(const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(stats_.last_error, sizeof stats_.last_error, fmt, ap);
  va_end(ap);
}

bool StereoCamera::format_fits(const hal::VideoFormat& f) noexcept {
  const int want_w = side_by_side_width(mode_);
  const int want_h = side_by_side_height(mode_);
  if (f.pixel_format != hal::kFourccYuyv || f.width != want_w || f.height != want_h) {
    char got[5];
    fourcc_chars(f.pixel_format, got);
    set_error("the stream delivers %s %dx%d but mode %s@%d needs YUYV %dx%d (two %dx%d eyes side by side): "
              "open the device with that format or choose the mode it runs",
              got, f.width, f.height, resolution_name(mode_.resolution), mode_.fps, want_w, want_h,
              mode_.eye_width, mode_.eye_height);
    return false;
  }
  const int min_bpl = yuyv_min_bytes_per_line(mode_);
  if (f.bytes_per_line < min_bpl) {
    set_error("the stream's lines are %d bytes apart, less than the %d bytes of a %d-pixel YUYV line",
              f.bytes_per_line, min_bpl, want_w);
    return false;
  }
  const std::size_t need = yuyv_frame_bytes(mode_, f.bytes_per_line);
  if (f.image_size < need) {
    set_error("the stream's image size %u bytes cannot hold %d lines of %d bytes (%zu bytes)", f.image_size,
              want_h, f.bytes_per_line, need);
    return false;
  }
  frame_bytes_ = f.image_size;
  // A reopen may come back with another line pitch: re-target the tables
  // in place (no allocation).
  if (f.bytes_per_line != rectifier_.bytes_per_line() && !rectifier_.set_bytes_per_line(f.bytes_per_line)) {
    set_error("the rectifier cannot take lines %d bytes apart", f.bytes_per_line);
    return false;
  }
  return true;
}

void StereoCamera::refresh_stream_stats() noexcept {
  stats_.stream = stream_.stats();
  stats_.stream.timeouts -= catch_up_timeouts_;
}

StereoStepOutcome StereoCamera::step(TimeNs timeout_ns, StereoFrameResult* result) noexcept {
  StereoFrameResult local;
  StereoFrameResult* r = result ? result : &local;
  *r = StereoFrameResult{};
  const std::int64_t dropped_before = stream_.stats().dropped;
  StereoStepOutcome out = StereoStepOutcome::kTimeout;
  if (down_) {
    out = step_down(timeout_ns);
  } else {
    for (int k = 0; k < config_.max_frames_per_step; ++k) {
      hal::VideoFrame frame;
      // Only the first dequeue waits; the others take what is already there.
      const hal::HalStatus s = stream_.dequeue(k == 0 ? timeout_ns : 0, &frame);
      if (s == hal::HalStatus::kOk) {
        const StereoStepOutcome o = handle_frame(frame, r);
        // A published frame is the step's news; otherwise the last problem.
        if (out != StereoStepOutcome::kFrame) out = o;
        if (o == StereoStepOutcome::kLost) break;
        continue;
      }
      if (s == hal::HalStatus::kTimeout) {
        if (k > 0) ++catch_up_timeouts_;
        break;
      }
      if (s == hal::HalStatus::kClosed) {
        out = go_down(clock_.now());
        break;
      }
      ++stats_.errors;
      set_error("%s: dequeue failed (%s): %s", kWho, hal::to_string(s), stream_.last_error());
      if (out != StereoStepOutcome::kFrame) {
        out = StereoStepOutcome::kError;
        // An error that repeats at once (a stream not streaming) must not
        // make the caller's loop spin: wait out this step's timeout.
        const TimeNs now = clock_.now();
        if (timeout_ns > 0) clock_.sleep_until(now + timeout_ns);
      }
      break;
    }
  }
  r->dropped = stream_.stats().dropped - dropped_before;
  r->outcome = out;
  refresh_stream_stats();
  return out;
}

StereoStepOutcome StereoCamera::handle_frame(const hal::VideoFrame& frame, StereoFrameResult* r) noexcept {
  ++stats_.frames;
  StereoStepOutcome out = StereoStepOutcome::kFrame;
  if (frame.bytes_used != frame_bytes_) {
    // A short (or long) frame has lines from two captures or none: never rectify it.
    ++stats_.rejected_size;
    set_error("%s: frame %u has %u bytes, expected %u (a partial frame); dropped", kWho, frame.sequence,
              frame.bytes_used, frame_bytes_);
    out = StereoStepOutcome::kRejected;
  } else if (frame.corrupted) {
    ++stats_.rejected_corrupted;
    set_error("%s: frame %u flagged as corrupted by the device; dropped", kWho, frame.sequence);
    out = StereoStepOutcome::kRejected;
  } else {
    FramePool::WriteSlot w = pool_.acquire();
    if (!w.valid()) {
      // Every slot is held by consumers: drop this frame rather than wait
      // (waiting would make the device drop frames instead, unseen).
      ++stats_.pool_full;
      out = StereoStepOutcome::kPoolFull;
    } else {
      const YuyvFrameView view{frame.data, frame.bytes_used, side_by_side_width(mode_), side_by_side_height(mode_),
                               rectifier_.bytes_per_line()};
      if (rectifier_.rectify(view, GreyImageView{w.left, w.stride}, GreyImageView{w.right, w.stride})) {
        // Before publish(), which takes the slot from this thread: every
        // published pair is in the digest, in publish order.
        stats_.pairs_digest = chain_pair_digest(stats_.pairs_digest, w.left, w.right, w.width, w.height, w.stride);
        r->frame_id = pool_.publish(w, frame.stamp, frame.sequence);
        r->stamp = frame.stamp;
        r->sequence = frame.sequence;
        ++r->published;
        ++stats_.rectified;
        if (stats_.rate_frames == 0) stats_.rate_first_stamp = frame.stamp;
        stats_.rate_last_stamp = frame.stamp;
        ++stats_.rate_frames;
      } else {
        // Cannot happen with a format that passed format_fits(); counted as
        // a size rejection rather than trusted.
        pool_.abandon(w);
        ++stats_.rejected_size;
        set_error("%s: frame %u does not fit the rectifier; dropped", kWho, frame.sequence);
        out = StereoStepOutcome::kRejected;
      }
    }
  }
  const hal::HalStatus s = stream_.release(frame.index);
  if (s == hal::HalStatus::kClosed) return go_down(clock_.now());
  if (s != hal::HalStatus::kOk) {
    ++stats_.errors;
    set_error("%s: giving buffer %d back failed (%s): %s", kWho, frame.index, hal::to_string(s),
              stream_.last_error());
  }
  return out;
}

StereoStepOutcome StereoCamera::go_down(TimeNs now) noexcept {
  ++stats_.lost;
  down_ = true;
  backoff_ = config_.reopen_backoff_initial_ns;
  next_reopen_ = now + backoff_;
  set_error("%s: the camera went away (%s); reopening in %lld ms", kWho, stream_.last_error(),
            static_cast<long long>(backoff_ / 1'000'000));
  return StereoStepOutcome::kLost;
}

StereoStepOutcome StereoCamera::step_down(TimeNs timeout_ns) noexcept {
  const TimeNs now = clock_.now();
  const TimeNs wait = timeout_ns > 0 ? timeout_ns : 0;
  const TimeNs step_deadline = wait > INT64_MAX - now ? INT64_MAX : now + wait;
  if (now < next_reopen_) {
    // Not due: sleep until it is, or until the step's time is up.
    clock_.sleep_until(next_reopen_ < step_deadline ? next_reopen_ : step_deadline);
    if (clock_.now() < next_reopen_) return StereoStepOutcome::kDown;
  }
  ++stats_.reopen_attempts;
  const TimeNs at = clock_.now();
  const hal::HalStatus s = stream_.reopen();
  if (s == hal::HalStatus::kOk) {
    if (!format_fits(stream_.format())) {
      // The device came back in another format: frames would be misread.
      // Stay down and keep trying at the slowest rate.
      ++stats_.errors;
      backoff_ = config_.reopen_backoff_max_ns;
      next_reopen_ = at + backoff_;
      stream_.stop();
      return StereoStepOutcome::kError;
    }
    down_ = false;
    backoff_ = config_.reopen_backoff_initial_ns;
    stats_.rate_frames = 0;
    return StereoStepOutcome::kReopened;
  }
  backoff_ = backoff_ > config_.reopen_backoff_max_ns / 2 ? config_.reopen_backoff_max_ns : 2 * backoff_;
  next_reopen_ = at + backoff_;
  set_error("%s: reopen failed (%s): %s; next try in %lld ms", kWho, hal::to_string(s), stream_.last_error(),
            static_cast<long long>(backoff_ / 1'000'000));
  // Do not return before the step's time is up, or a caller looping on
  // step() would spin while the device is away.
  const TimeNs after = clock_.now();
  const TimeNs end = step_deadline > after ? step_deadline : after;
  clock_.sleep_until(next_reopen_ < end ? next_reopen_ : end);
  return StereoStepOutcome::kDown;
}

}  // namespace rtfuse::drivers
