#pragma once
// A device that runs on a thread of its own (the IMU today; a camera, a
// serial GNSS receiver): it waits on its device with a timeout, turns what
// came into samples for its sensor's ring, and reports its health through a
// seqlock the loop reads. The live runtime gives each one a thread; the HAL
// replay and the simulated drive step them in lockstep with the ticks. No
// device is special-cased in any of the three.
#include <cstdint>

#include "core/time.hpp"
#include "runtime/fusion/snapshot.hpp"

namespace rtfuse {

// How long one step waits for its device (an edge, a frame, bytes). Live
// runs, lockstep drives and replays pass the same value, because a
// recording holds the wait's arguments and its replay must make the same
// calls; it also bounds how long a stop request waits.
constexpr TimeNs kDeviceStepTimeoutNs = 50'000'000;

class ThreadDevice {
 public:
  virtual ~ThreadDevice() = default;
  // Short name: the thread is "rtfuse-<name>" and its bus calls are the
  // recording stream of that name.
  virtual const char* name() const noexcept = 0;
  // Device thread: wait at most timeout_ns, read, push samples. Never
  // allocates or locks (outside a re-initialisation after a device loss).
  virtual void step(TimeNs timeout_ns) noexcept = 0;
  // The sensor whose ring it feeds (-1: none) and the samples pushed so far:
  // a replay steps the device until the loop's recorded intake is reached.
  virtual int sensor() const noexcept = 0;
  virtual std::int64_t samples() const noexcept = 0;
  // Loop thread: health into the snapshot's device slots.
  virtual void fill_snapshot(Snapshot& s) noexcept = 0;
};

}  // namespace rtfuse
