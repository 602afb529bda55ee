#pragma once
// A ZED-class stereo camera on a hal::VideoStream: dequeues side-by-side YUYV
// frames, checks them, rectifies each into a FramePool slot (left and right
// grey, stamped with the capture time and the device's sequence number),
// publishes it and gives the buffer straight back to the device.
//
// No threads, no system calls, no allocation after create(): the caller's
// camera thread calls step() in a loop. The only blocking is the stream's
// dequeue wait and, while the camera is unplugged, a sleep on the hal::Clock
// until the next reopen attempt (never a busy loop).
//
// Unplug handling: dequeue() giving kClosed puts the driver in a down state;
// each step then calls reopen() only once the backoff deadline has passed,
// doubling the backoff after every failure up to the maximum, and resetting
// it after a success.
#include <cstdint>
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "core/time.hpp"
#include "drivers/camera/camera_modes.hpp"
#include "drivers/camera/stereo_calibration.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "drivers/camera/stereo_rectifier.hpp"
#include "hal/clock.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::drivers {

struct StereoCameraConfig {
  std::string resolution = "HD";  // "2K", "FHD", "HD", "VGA" (camera_modes.hpp)
  int fps = 30;
  // When not 0, the calibration must be this camera's (calibration_serial).
  std::int64_t expected_serial = 0;
  // Serial of the factory file the calibration came from (ZedCalibration::serial).
  std::int64_t calibration_serial = 0;
  StereoCalibration calibration;  // for `resolution`, already loaded by the caller
  TimeNs reopen_backoff_initial_ns = 250'000'000;
  TimeNs reopen_backoff_max_ns = 8'000'000'000;
  // Frames handled per step: the first dequeue waits, the rest only take
  // frames already captured (a late step catches up instead of falling
  // further behind). 1 is exactly one dequeue per step.
  int max_frames_per_step = 1;
};

enum class StereoStepOutcome : std::uint8_t {
  kFrame,     // at least one frame rectified and published
  kTimeout,   // nothing came within the timeout
  kRejected,  // frame(s) refused: wrong bytes_used or flagged corrupted
  kPoolFull,  // every pool slot was held: the frame was dropped
  kLost,      // the device went away this step; now down
  kDown,      // still down; no reopen was due, or it failed
  kReopened,  // the device is back; frames follow on the next steps
  kError,     // the stream failed otherwise (see stats().last_error)
};
const char* to_string(StereoStepOutcome outcome) noexcept;

struct StereoFrameResult {
  StereoStepOutcome outcome = StereoStepOutcome::kTimeout;
  int published = 0;  // frames published this step
  // The last frame published this step (published > 0).
  std::uint64_t frame_id = 0;
  TimeNs stamp = 0;
  std::uint32_t sequence = 0;
  // Frames the device dropped before this step's frames (sequence gaps).
  std::int64_t dropped = 0;
};

struct StereoCameraStats {
  std::int64_t frames = 0;              // buffers dequeued by the driver
  std::int64_t rectified = 0;           // rectified and published
  std::int64_t rejected_size = 0;       // bytes_used other than the frame size
  std::int64_t rejected_corrupted = 0;  // flagged by the device
  std::int64_t pool_full = 0;           // dropped: no free pool slot
  std::int64_t errors = 0;              // other stream failures
  std::int64_t lost = 0;                // times the driver saw the device go
  std::int64_t reopen_attempts = 0;
  // The stream's own counters (sequence drops and gaps, timeouts, lost,
  // reopens, reopen failures), as of the end of the last step. Empty
  // dequeues made only to catch up (max_frames_per_step > 1) are not
  // counted as timeouts.
  hal::VideoStreamStats stream;
  // Frame-rate input: capture stamps of the published frames since start or
  // the last reopen (a gap while unplugged is not a slow frame).
  TimeNs rate_first_stamp = 0;
  TimeNs rate_last_stamp = 0;
  std::int64_t rate_frames = 0;
  // Measured rate from the stamps above; 0 with fewer than two frames.
  double measured_fps() const noexcept {
    if (rate_frames < 2 || rate_last_stamp <= rate_first_stamp) return 0.0;
    return static_cast<double>(rate_frames - 1) * 1e9 / static_cast<double>(rate_last_stamp - rate_first_stamp);
  }
  // XXH64 chained over every published pair in publish order (see
  // chain_pair_digest): equal after two runs exactly when every pair they
  // published was the same, byte for byte. 0 before the first pair.
  std::uint64_t pairs_digest = 0;
  char last_error[256] = {};
};

// The running digest after one more rectified pair: XXH64 (core/xxh64.hpp)
// of the left eye's rows then the right eye's, width bytes of each row (the
// padding up to stride is not part of the image), seeded with the digest of
// the pairs before it. Integer-only: the same value on every architecture.
std::uint64_t chain_pair_digest(std::uint64_t previous, const std::uint8_t* left, const std::uint8_t* right,
                                int width, int height, int stride) noexcept;

class StereoCamera {
 public:
  // Checks the mode, the calibration (size, serial) and the stream's
  // negotiated format (YUYV, 2 x eye width by eye height, a whole frame per
  // buffer) and the pool's size against each other; builds the
  // rectification and the rectifier tables; starts the stream. Null with
  // *error saying what does not match and what to do. Allocates (start-up).
  static std::unique_ptr<StereoCamera> create(const StereoCameraConfig& config, hal::VideoStream& stream,
                                              hal::Clock& clock, FramePool& pool, std::string* error);
  StereoCamera(const StereoCamera&) = delete;
  StereoCamera& operator=(const StereoCamera&) = delete;

  // One step (see StereoStepOutcome). Waits at most timeout_ns.
  StereoStepOutcome step(TimeNs timeout_ns, StereoFrameResult* result) noexcept;

  bool down() const noexcept { return down_; }
  // When the next reopen is attempted (while down).
  TimeNs next_reopen_ns() const noexcept { return next_reopen_; }
  TimeNs reopen_backoff_ns() const noexcept { return backoff_; }
  const StereoCameraStats& stats() const noexcept { return stats_; }
  // The rectified pinhole (fx, fy, cx, cy), baseline and Q for consumers.
  const StereoRectification& rectified() const noexcept { return rectification_; }
  const CameraMode& mode() const noexcept { return mode_; }

 private:
  StereoCamera(const StereoCameraConfig& config, const CameraMode& mode, hal::VideoStream& stream,
               hal::Clock& clock, FramePool& pool, const StereoRectification& rectification);
  // One dequeued buffer: checked, rectified, published, released.
  StereoStepOutcome handle_frame(const hal::VideoFrame& frame, StereoFrameResult* result) noexcept;
  StereoStepOutcome go_down(TimeNs now) noexcept;
  StereoStepOutcome step_down(TimeNs timeout_ns) noexcept;
  // The stream's format fits the mode (after create and after every reopen);
  // false with last_error set.
  bool format_fits(const hal::VideoFormat& format) noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));
  void refresh_stream_stats() noexcept;

  StereoCameraConfig config_;
  CameraMode mode_;
  hal::VideoStream& stream_;
  hal::Clock& clock_;
  FramePool& pool_;
  StereoRectification rectification_;
  StereoRectifier rectifier_;
  StereoCameraStats stats_;
  std::uint32_t frame_bytes_ = 0;  // bytes_used of a good frame
  bool down_ = false;
  TimeNs backoff_ = 0;
  TimeNs next_reopen_ = 0;
  std::int64_t catch_up_timeouts_ = 0;  // empty catch-up dequeues (not real timeouts)
};

}  // namespace rtfuse::drivers
