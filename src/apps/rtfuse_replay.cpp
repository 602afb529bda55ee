// rtfuse-replay: runs the runtime in lockstep with an LCM event log, as fast
// as the CPU allows, and prints the final state as one JSON line.
#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "runtime/config_loader.hpp"
#include "runtime/replay.hpp"

namespace {

void print_json(const rtfuse::RuntimeConfig& cfg, const rtfuse::ReplayResult& r) {
  const rtfuse::Snapshot& s = r.final;
  static const char* kKeys[] = {"x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz"};
  std::printf("{");
  for (int i = 0; i < 9; ++i) std::printf("\"%s\": %.17g, ", kKeys[i], s.state[i]);
  std::printf("\"initialized\": %s, \"events\": %" PRId64 ", \"ticks\": %" PRId64 ", \"published\": %" PRId64
              ", \"unknown_channel_messages\": %" PRId64 ", \"sensors\": {",
              s.initialized ? "true" : "false", r.events, r.ticks, r.published, s.unknown_channel_messages);
  for (int i = 0; i < s.num_sensors; ++i) {
    const rtfuse::SensorStats& st = s.sensors[i];
    const std::int64_t rejected = st.rejected_mahalanobis + st.rejected_invalid + st.rejected_stale +
                                  st.rejected_overflow + st.decode_errors;
    std::printf("%s\"%s\": {\"received\": %" PRId64 ", \"accepted\": %" PRId64 ", \"rejected\": %" PRId64
                ", \"rejected_mahalanobis\": %" PRId64 ", \"rejected_invalid\": %" PRId64
                ", \"rejected_stale\": %" PRId64 ", \"rejected_overflow\": %" PRId64 ", \"decode_errors\": %" PRId64
                ", \"yaw_conflicts\": %" PRId64 "}",
                i ? ", " : "", cfg.sensors[i].name.c_str(), st.received, st.accepted, rejected,
                st.rejected_mahalanobis, st.rejected_invalid, st.rejected_stale, st.rejected_overflow,
                st.decode_errors, st.yaw_conflicts);
  }
  std::printf("}}\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtfuse-replay: run rtfuse in lockstep with an LCM log (lcm-logger format)"};
  std::string config_path, log_path, out_path;
  bool quiet = false;
  app.add_option("-c,--config", config_path, "TOML config")->required();
  app.add_option("-l,--log", log_path, "input LCM log")->required();
  app.add_option("-o,--out", out_path, "write the published channels to this LCM log");
  app.add_flag("-q,--quiet", quiet, "no progress line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help is a ParseError with exit code 0; every real error is a usage error (2).
    return app.exit(e) == 0 ? 0 : 2;
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
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
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
  print_json(cfg, r);
  return 0;
}
