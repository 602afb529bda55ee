#pragma once
// A device as the runtime drives it: polled by the loop inside its tick (the
// CANopen wheel encoders), on a thread of its own (the IMU, the camera, a
// GNSS receiver), or as a frame consumer of another device (the visual
// odometry on the camera's pairs). Its measurements enter the fusion through
// the same sensor rings as decoded LCM messages, and its health crosses to
// the loop as DeviceStatus slots. The live runtime, the HAL replay and the
// simulated drive treat every device through this interface alone; what
// kind of device it is, its descriptor says (device_descriptor.hpp).
//
// Everything is allocated in the descriptor's create(); poll(), step(),
// fill_snapshot() and publish_due() allocate nothing (outside a device's
// re-initialisation after a loss).
#include <cstdint>
#include <string>

#include "core/time.hpp"
#include "runtime/fusion/snapshot.hpp"
#include "transport/message_sink.hpp"

namespace rtfuse {

class FrameConsumer;
class FrameSource;
class GridConsumer;
class GridSource;

// How long one thread step waits for its device (an edge, a frame, bytes).
// Live runs, lockstep drives and replays pass the same value, because a
// recording holds the wait's arguments and its replay must make the same
// calls; it also bounds how long a stop request waits.
constexpr TimeNs kDeviceStepTimeoutNs = 50'000'000;

class Device {
 public:
  virtual ~Device() = default;

  // Before any thread: identity checks, NMT start. False with *error naming
  // the device and the fix.
  virtual bool start(TimeNs now, std::string* error) {
    (void)now;
    (void)error;
    return true;
  }
  // Polled devices, on the loop thread before the rings are drained.
  virtual void poll(TimeNs now) noexcept { (void)now; }
  // Thread devices, on their thread: wait at most timeout_ns, read, push
  // samples. Never allocates or locks.
  virtual void step(TimeNs timeout_ns) noexcept { (void)timeout_ns; }
  // The sensor whose ring its thread feeds (-1: none) and the samples pushed
  // so far: a replay steps the thread until the loop's recorded intake.
  virtual int sensor() const noexcept { return -1; }
  virtual std::int64_t samples() const noexcept { return 0; }
  // Workers (DeviceScheduling::kWorker), once every thread has stopped:
  // finish the work the run's last tick made due, so a live run, its replay
  // and a lockstep drive end in the same state.
  virtual void finish() noexcept {}
  // Loop thread: its health into its diagnostics slots of the snapshot.
  virtual void fill_snapshot(Snapshot& s) noexcept = 0;
  // Publisher thread: outputs of its own that are for watching, not for the
  // estimate (a camera's preview), so neither recorded nor compared.
  virtual void publish_due(TimeNs now, transport::MessageSink& sink) noexcept {
    (void)now;
    (void)sink;
  }
  // A device whose pairs others consume, and a consumer of them.
  virtual FrameSource* frame_source() noexcept { return nullptr; }
  virtual FrameConsumer* frame_consumer() noexcept { return nullptr; }
  // A device whose 2-D grid others plan on (the mapper), and a consumer of it.
  virtual GridSource* grid_source() noexcept { return nullptr; }
  virtual GridConsumer* grid_consumer() noexcept { return nullptr; }
  // LCM messages on the channels its descriptor's input_channels() names
  // (channel is one of them), from whichever thread delivers them: the
  // LCM thread live, the replay or the simulator's goal sequence in
  // lockstep. Decoded there and handed to the loop through a ring; never
  // blocks. `now` is the arrival time.
  virtual void on_input(int channel, const std::uint8_t* data, int size, TimeNs now) noexcept {
    (void)channel;
    (void)data;
    (void)size;
    (void)now;
  }
  // Loop thread: the messages of that input channel the loop has taken so
  // far (a recording's tick keeps it, so a replay delivers them in time).
  virtual std::int64_t inputs_taken(int channel) const noexcept {
    (void)channel;
    return 0;
  }
};

}  // namespace rtfuse
