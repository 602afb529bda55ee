#pragma once
// The socket through which a camera's rectified pairs reach the code that
// uses them: the visual odometry (every pair, on the camera's thread), a
// mapper (keyframes, on a thread of its own), a test's probe. A consumer
// plugs in at start-up without the camera or any other consumer changing.
//
// Pairs never move: the source lends the newest one by handle from its
// FramePool (core/frame_pool.hpp) for the length of on_pair(); a consumer
// that works on it later keeps its own reference (FramePool::retain, or a
// FrameMailbox). The pool is sized so that every consumer holding what it
// declares still leaves capture a free slot: a slow consumer drops pairs
// (and counts them), it never stalls capture, the loop or another consumer.
#include <cstdint>
#include <string>

#include "core/frame_pool.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "hal/clock.hpp"

namespace rtfuse {

class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  virtual const char* name() const noexcept = 0;
  // Pairs it may still hold after on_pair() returns (0: it reads the pair
  // only during the call; a consumer with a thread of its own holds up to 2,
  // one waiting and one in work).
  virtual int frames_held() const noexcept { return 0; }
  // The source's thread, once per step that published a pair: `newest` is
  // that pair, held by the source for the call. Must return without
  // blocking; work beyond a pair period belongs on the consumer's thread.
  virtual void on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept = 0;
  // The sensor whose ring it feeds from the source's thread (-1: none) and
  // the samples pushed so far: a replay steps the source's thread until the
  // loop's recorded intake of that sensor.
  virtual int sensor() const noexcept { return -1; }
  virtual std::int64_t samples() const noexcept { return 0; }
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Start-up only, before the source's thread runs. False with *error when
  // the pool cannot lend the consumer what it holds without starving capture
  // (the fix: a larger pool_frames), or too many consumers are attached.
  virtual bool attach(FrameConsumer& consumer, std::string* error) = 0;
  virtual FramePool& pool() noexcept = 0;
  virtual const drivers::StereoRectification& rectified() const noexcept = 0;
  // The clock the pairs' stamps are on (a consumer's latency figures).
  virtual hal::Clock& clock() noexcept = 0;
};

}  // namespace rtfuse
