#pragma once
// Hardware-in-the-loop replay of a recording made with rtfused --record (or
// rtfuse-sim): the same drivers, FusionCore and Publisher as the daemon run
// on replay buses that hand back the recorded bytes. Each recorded loop tick
// is replayed at its recorded time, after the IMU driver has produced exactly
// the samples the live loop had taken by then, so the estimate and every
// published estimate message come out byte for byte as recorded.
//
// A driver that asks for a different transfer than the recorded one (other
// CAN frame, other I2C register, ...) stops the replay with the divergence
// report of the replay stream: log event number, recorded call, attempted call.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "runtime/config/config.hpp"
#include "runtime/fusion/snapshot.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse {

struct HalReplayResult {
  bool ok = false;            // no set-up error and no divergence (ended_early: stopped before the last tick)
  std::string error;          // set up failed, or the divergence report
  bool diverged = false;
  bool ended_early = false;   // a stream ran out before the last tick (truncated, lost events)
  std::string note;           // why it ended early
  std::int64_t ticks = 0;
  std::int64_t published = 0;  // messages the replay published
  // Estimate outputs (everything but diagnostics, whose loop timings measure
  // the live machine) compared with the recorded ones, per channel in order.
  std::int64_t compared = 0;
  std::int64_t identical = 0;
  std::int64_t recorded_not_reproduced = 0;  // recorded messages the replay did not publish
  std::string first_mismatch;                // "" when every compared message was identical
  Snapshot final;
};

struct HalReplayProgress {
  std::int64_t ticks = 0;
  std::int64_t total_ticks = 0;
};

// cfg must be the recording's configuration (check_recording_config).
HalReplayResult replay_hal_recording(const HalRecording& rec, const RuntimeConfig& cfg,
                                     transport::EventLogWriter* out,
                                     const std::function<void(const HalReplayProgress&)>& progress);

// "" when config_text is the one the recording was made with; otherwise a
// message naming both hashes and files.
std::string check_recording_config(const transport::RecordingInfo& info, const std::string& config_text,
                                   const std::string& config_path);

}  // namespace rtfuse
