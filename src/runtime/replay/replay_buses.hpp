#pragma once
// The buses a HAL recording gives back to the devices of its configuration:
// for every enabled registered device, the recorded buses of its stream
// ("loop" for a polled device, its own name for a thread device), matched by
// kind and recorded name, as replay buses that hand back each recorded call
// after checking it is the same call. A device whose clock was not recorded
// gets a free-running clock the replay sets to each tick's time. Start-up
// only: binding allocates.
#include <memory>
#include <string>
#include <vector>

#include "hal/clock.hpp"
#include "hal/replay/replay_stream.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/replay/hal_recording.hpp"

namespace rtfuse {

// A clock nothing recorded: it reads what it was last set to, and a wait
// ends at once, at its deadline (a camera's back-off while unplugged). A
// recording whose camera was unplugged may therefore diverge at a reopen,
// and says so, but never replays differently in silence.
class FreeRunningClock final : public hal::Clock {
 public:
  TimeNs now() const noexcept override { return now_; }
  void sleep_until(TimeNs t) noexcept override {
    if (t > now_) now_ = t;
  }

 private:
  TimeNs now_ = 0;
};

// What one device replays from.
struct ReplayedDevice {
  hal::replay::ReplayStream* stream = nullptr;    // its stream's bus calls; null: none recorded
  hal::replay::ReplayVideoLog* video = nullptr;   // its camera calls, when it has a video stream
  FreeRunningClock* free_clock = nullptr;         // when its clock was not recorded
};

class ReplayBuses {
 public:
  // Null with *error naming the section and what the recording lacks.
  static std::unique_ptr<ReplayBuses> bind(const HalRecording& rec, const RuntimeConfig& cfg,
                                           std::string* error);
  const HalBuses& buses() const { return buses_; }
  // By registered device name (a thread device's, Hardware::thread_device_name).
  const ReplayedDevice& device(std::string_view name) const;

 private:
  ReplayBuses() = default;
  HalBuses buses_;
  ReplayedDevice devices_[kMaxDeviceTypes];
  BusKeeper keep_;
  std::vector<std::unique_ptr<FreeRunningClock>> clocks_;
};

}  // namespace rtfuse
