// rtfuse-replay: runs the runtime in lockstep with an LCM event log, as fast
// as the CPU allows, and prints the final state as one JSON line.
//
// Two kinds of log: an ordinary one (lcm-logger, rosbag_to_lcm.py) whose
// input channels are decoded as live; or a HAL recording (rtfused --record,
// rtfuse-sim), replayed through the drivers on replay buses, checked call by
// call against the recording and output by output against what was
// published when it was made.
#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <string>

#include "apps/command_line.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "runtime/replay/replay.hpp"
#include "transport/hal_record_codec.hpp"

namespace {

void print_json(const rtfuse::RuntimeConfig& cfg, const rtfuse::Snapshot& s, std::int64_t events, std::int64_t ticks,
                std::int64_t published, const std::string& extra) {
  static const char* kKeys[] = {"x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz"};
  std::printf("{");
  for (int i = 0; i < 9; ++i) std::printf("\"%s\": %.17g, ", kKeys[i], s.state[i]);
  std::printf("\"initialized\": %s, \"events\": %" PRId64 ", \"ticks\": %" PRId64 ", \"published\": %" PRId64
              ", \"unknown_channel_messages\": %" PRId64 ", \"sensors\": {",
              s.initialized ? "true" : "false", events, ticks, published, s.unknown_channel_messages);
  for (int i = 0; i < s.num_sensors; ++i) {
    const rtfuse::SensorStats& st = s.sensors[i];
    std::printf("%s\"%s\": {\"received\": %" PRId64 ", \"accepted\": %" PRId64 ", \"rejected\": %" PRId64
                ", \"rejected_mahalanobis\": %" PRId64 ", \"rejected_invalid\": %" PRId64
                ", \"rejected_stale\": %" PRId64 ", \"rejected_overflow\": %" PRId64 ", \"rejected_rate\": %" PRId64
                ", \"rejected_oversize\": %" PRId64 ", \"decode_errors\": %" PRId64 ", \"yaw_conflicts\": %" PRId64
                "}",
                i ? ", " : "", rtfuse::qualified_sensor_name(cfg, i).c_str(), st.received, st.accepted, rtfuse::rejected_total(st),
                st.rejected_mahalanobis, st.rejected_invalid, st.rejected_stale, st.rejected_overflow,
                st.rejected_rate, st.rejected_oversize, st.decode_errors, st.yaw_conflicts);
  }
  // Device health at the end (a HAL recording's): what rtfused prints when it stops.
  std::printf("}, \"devices\": {");
  for (int i = 0; i < s.num_devices; ++i) {
    const rtfuse::DeviceStatus& d = s.devices[i];
    std::printf("%s\"%s\": {\"state\": \"%s\"", i ? ", " : "", d.name.c_str(), d.state.c_str());
    for (int k = 0; k < d.num_values; ++k) std::printf(", \"%s\": %" PRId64, d.keys[k], d.values[k]);
    std::printf("}");
  }
  // Every filter instance by name, the first included (its values are the
  // top-level keys too).
  std::printf("}, \"instances\": {");
  for (int k = 0; k < s.num_instances; ++k) {
    const rtfuse::InstanceSnapshot& in = s.instances[k];
    const double* state = k == 0 ? s.state : in.state;
    std::printf("%s\"%s\": {", k ? ", " : "", cfg.instances[static_cast<std::size_t>(k)].name.c_str());
    for (int i = 0; i < 9; ++i) std::printf("\"%s\": %.17g, ", kKeys[i], state[i]);
    std::printf("\"world_frame\": \"%s\", \"initialized\": %s, \"fixes_fused\": %" PRId64,
                rtfuse::instance_world_frame(cfg, k).c_str(), in.initialized ? "true" : "false", in.fixes_fused);
    if (in.has_map_odom) {
      std::printf(", \"map_odom\": [%.17g, %.17g, %.17g]", in.map_odom_translation[0], in.map_odom_translation[1],
                  in.map_odom_translation[2]);
    }
    std::printf("}");
  }
  std::printf("}%s}\n", extra.c_str());
}

enum class LogKind { kHalRecording, kLcmLog, kEmpty, kUnreadable };

// What the log is, from its first event; kUnreadable with the reader's
// words (cannot open, a directory, truncated, not an LCM log).
LogKind classify_log(const std::string& path, std::string* error) {
  rtfuse::transport::EventLogReader in;
  rtfuse::transport::LogEvent ev;
  if (!in.open(path, error)) return LogKind::kUnreadable;
  switch (in.next(&ev, error)) {
    case rtfuse::transport::ReadStatus::kEvent:
      return ev.channel == rtfuse::transport::kRecordingInfoChannel ? LogKind::kHalRecording : LogKind::kLcmLog;
    case rtfuse::transport::ReadStatus::kEnd:
      return LogKind::kEmpty;
    case rtfuse::transport::ReadStatus::kError:
      break;
  }
  return LogKind::kUnreadable;
}


int replay_recording(const std::string& log_path, const std::string& config_path, const std::string& out_path,
                     bool allow_truncated, std::uint64_t frame_memory_mib, bool tty) {
  rtfuse::transport::EventLogReader in;
  std::string error;
  if (!in.open(log_path, &error)) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  rtfuse::HalRecording rec;
  rtfuse::HalRecordingOptions options;
  options.allow_truncated = allow_truncated;
  options.max_frame_bytes = frame_memory_mib << 20;
  if (!rtfuse::load_hal_recording(in, options, &rec, &error)) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  for (const std::string& w : rec.warnings) std::fprintf(stderr, "rtfuse-replay: warning: %s\n", w.c_str());
  // The recording carries its configuration; another one must be the same.
  std::string text = rec.info.config_text;
  std::string source = rec.info.config_path;
  if (!config_path.empty()) {
    std::string given;
    int err = 0;
    if (!rtfuse::read_text_file(config_path, &given, &err)) {
      std::fprintf(stderr, "rtfuse-replay: cannot read %s: %s\n", config_path.c_str(), std::strerror(err));
      return 2;
    }
    const std::string mismatch = rtfuse::check_recording_config(rec.info, given, config_path);
    if (!mismatch.empty()) {
      std::fprintf(stderr, "rtfuse-replay: %s\n", mismatch.c_str());
      return 2;
    }
    text = given;
    source = config_path;
  }
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(text, source);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  const rtfuse::RuntimeConfig& cfg = *loaded.config;
  rtfuse::transport::EventLogWriter out;
  if (!out_path.empty() && !out.open(out_path, &error)) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  const rtfuse::HalReplayResult r = rtfuse::replay_hal_recording(
      rec, cfg, out_path.empty() ? nullptr : &out, [tty](const rtfuse::HalReplayProgress& p) {
        if (tty) std::fprintf(stderr, "\rreplay: tick %" PRId64 " of %" PRId64 "\033[K", p.ticks, p.total_ticks);
      });
  if (tty) std::fprintf(stderr, "\n");
  if (!out_path.empty() && !out.close(&error) && r.ok) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  if (!r.note.empty()) std::fprintf(stderr, "rtfuse-replay: %s\n", r.note.c_str());
  if (r.ok && r.ended_early && !allow_truncated) {
    std::fprintf(stderr,
                 "rtfuse-replay: the recording is incomplete (%" PRId64 " recorded outputs not reproduced); "
                 "--allow-truncated accepts the part that is there\n",
                 r.recorded_not_reproduced);
    return 1;
  }
  if (!r.ok) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", r.error.c_str());
    return r.diverged ? 3 : 1;
  }
  char extra[512];
  std::snprintf(extra, sizeof extra,
                ", \"recording\": {\"outputs_compared\": %" PRId64 ", \"outputs_identical\": %" PRId64
                ", \"recorded_not_reproduced\": %" PRId64 ", \"ended_early\": %s}",
                r.compared, r.identical, r.recorded_not_reproduced, r.ended_early ? "true" : "false");
  print_json(cfg, r.final, rec.events, r.ticks, r.published, extra);
  if (!r.first_mismatch.empty()) {
    std::fprintf(stderr, "rtfuse-replay: the replay does not reproduce the recorded outputs: %s\n",
                 r.first_mismatch.c_str());
    return 4;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-replay: run rtfuse in lockstep with an LCM log (lcm-logger format)"};
  std::string config_path, log_path, out_path;
  bool quiet = false;
  bool allow_truncated = false;
  std::uint64_t frame_memory_mib = rtfuse::HalRecordingOptions{}.max_frame_bytes >> 20;
  cli.option("-c,--config", &config_path,
                 "TOML config (required for an ordinary log; a HAL recording carries its own)");
  cli.option("-l,--log", &log_path, "input LCM log").required();
  cli.option("-o,--out", &out_path, "write the published channels to this LCM log");
  cli.flag("--allow-truncated", &allow_truncated,
               "replay the complete part of a HAL recording whose recorder was killed");
  cli.option("--frame-memory", &frame_memory_mib,
                 "MiB a HAL recording's camera frames may take in memory (each padded to its buffer)")
      .range(1, 1 << 24)
      .show_default();
  cli.flag("-q,--quiet", &quiet, "no progress line");
  if (const auto exit = cli.parse(argc, argv)) return *exit;

  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  std::string why;
  const LogKind kind = classify_log(log_path, &why);
  if (kind == LogKind::kUnreadable) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", why.c_str());
    return 1;
  }
  if (kind == LogKind::kHalRecording) {
    return replay_recording(log_path, config_path, out_path, allow_truncated, frame_memory_mib, tty);
  }
  // An empty log with --config replays nothing: how tools/deploy.sh has a
  // configuration checked by the loop that will run it.
  if (kind == LogKind::kEmpty && config_path.empty()) {
    std::fprintf(stderr, "rtfuse-replay: %s is empty: no event to replay (with --config it checks the configuration)\n",
                 log_path.c_str());
    return 1;
  }
  if (config_path.empty()) {
    std::fprintf(stderr, "rtfuse-replay: %s is not a HAL recording: give its configuration with --config\n",
                 log_path.c_str());
    return 2;
  }
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_file(config_path);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  const rtfuse::RuntimeConfig& cfg = *loaded.config;
  std::string error;
  auto replay = rtfuse::Replay::create(cfg, &error);
  if (!replay) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 2;
  }
  rtfuse::transport::EventLogReader in;
  if (!in.open(log_path, &error)) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  rtfuse::transport::EventLogWriter out;
  if (!out_path.empty() && !out.open(out_path, &error)) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  const rtfuse::ReplayResult r = replay->run(in, out_path.empty() ? nullptr : &out,
                                             [tty](const rtfuse::ReplayProgress& p) {
                                               if (tty) {
                                                 std::fprintf(stderr, "\rreplay: %" PRId64 " events, %.1f s of log\033[K",
                                                              p.events, rtfuse::ns_to_sec(p.log_time));
                                               }
                                             });
  if (tty) std::fprintf(stderr, "\n");
  if (!out_path.empty() && !out.close(&error) && r.ok) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", error.c_str());
    return 1;
  }
  if (!r.ok) {
    std::fprintf(stderr, "rtfuse-replay: %s\n", r.error.c_str());
    return 1;
  }
  print_json(cfg, r.final, r.events, r.ticks, r.published, "");
  return 0;
}
