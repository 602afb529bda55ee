// load_hal_recording: a HAL recording's records split into the replay
// streams of their threads, ticks and outputs; logs cut short, from another
// format version, with an undecodable event, an event after the end record
// or a hole in a stream; the files the configuration names.
#include "runtime/replay/hal_recording.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "support/hal_record_samples.hpp"
#include "support/recording_end.hpp"
#include "support/temp_file.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse {
namespace hal_recording_test {

using namespace transport;  // NOLINT: the records this loads are transport's
using hal::BusEvent;
using hal::BusEventKind;
using test::calibration_file;
using test::every_kind;
using test::sample_info;

// A log path of this test, removed afterwards.
class TempLog : public test::TempFile {
 public:
  explicit TempLog(const std::string& name) : TempFile("loader_" + name, ".lcm") {}
};

void write_recording(const std::string& path, const std::vector<BusEvent>& evs, bool with_info = true,
                     bool with_end = true) {
  const RecordingInfo info = sample_info();
  HalRecordCodec codec(info.devices);
  EventLogWriter w;
  std::string err;
  ASSERT_TRUE(w.open(path, &err)) << err;
  if (with_info) {
    const auto bytes = encode_recording_info(info);
    ASSERT_TRUE(w.write(5'000'000, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
  }
  std::uint8_t buf[kMaxHalRecordSize];
  std::int64_t seq = 0;
  for (const BusEvent& ev : evs) {
    const int n = codec.encode(ev, buf, sizeof buf);
    ASSERT_GT(n, 0);
    ASSERT_TRUE(w.write(ns_to_utime(ev.time_ns), codec.channel(ev.device), buf, static_cast<std::size_t>(n), &err));
    const std::int64_t consumed[2] = {seq, 2 * seq};
    const int t = codec.encode_tick(seq * 5'000'000, seq, consumed, 2, 0u, buf, sizeof buf);
    ASSERT_TRUE(w.write(seq * 5'000, std::string(kLoopTickChannel), buf, static_cast<std::size_t>(t), &err));
    ++seq;
  }
  const std::uint8_t out[3] = {1, 2, 3};
  ASSERT_TRUE(w.write(77, "rtfuse/odometry", out, sizeof out, &err));
  if (with_end) {
    ASSERT_TRUE(test::write_recording_end(w, 77, &err)) << err;
  }
  ASSERT_TRUE(w.close(&err)) << err;
}

std::vector<BusEvent> canonical_kinds() {
  std::vector<BusEvent> evs = every_kind();
  evs[0].lost_before = 0;  // not a hole
  return evs;
}

bool load(const std::string& path, HalRecording* rec, std::string* err, bool allow_truncated = false) {
  EventLogReader reader;
  if (!reader.open(path, err)) return false;
  HalRecordingOptions opts;
  opts.allow_truncated = allow_truncated;
  return load_hal_recording(reader, opts, rec, err);
}

TEST(HalRecordingLoader, SplitsEventsIntoStreamsTicksAndOutputs) {
  TempLog log("load");
  const std::vector<BusEvent> evs = canonical_kinds();
  write_recording(log.path(), evs);
  HalRecording rec;
  std::string err;
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  EXPECT_EQ(rec.info.streams, sample_info().streams);
  ASSERT_EQ(rec.streams.size(), 2u);
  // loop: can0 (devices 0), led (3) and gnss0 (5); imu: i2c-1, imu-drdy, imu-clock.
  std::vector<BusEvent> loop, imu;
  for (const BusEvent& ev : evs) (ev.device == 0 || ev.device == 3 || ev.device == 5 ? loop : imu).push_back(ev);
  ASSERT_EQ(rec.streams[0]->size(), loop.size());
  ASSERT_EQ(rec.streams[1]->size(), imu.size());
  for (std::size_t i = 0; i < loop.size(); ++i) EXPECT_EQ(rec.streams[0]->event(i), loop[i]) << i;
  for (std::size_t i = 0; i < imu.size(); ++i) EXPECT_EQ(rec.streams[1]->event(i), imu[i]) << i;
  // Event numbers: info is 0, then bus event / tick pairs.
  EXPECT_EQ(rec.streams[0]->log_event(0), 1);
  EXPECT_EQ(rec.streams[1]->log_event(0), 5);
  EXPECT_EQ(rec.streams[0]->name(), "loop");
  ASSERT_EQ(rec.ticks.size(), evs.size());
  EXPECT_EQ(rec.ticks[3].seq, 3);
  EXPECT_EQ(rec.ticks[3].time_ns, 15'000'000);
  EXPECT_EQ(rec.ticks[3].consumed, (std::vector<std::int64_t>{3, 6}));
  ASSERT_EQ(rec.outputs.size(), 1u);
  EXPECT_EQ(rec.outputs[0].channel, "rtfuse/odometry");
  EXPECT_EQ(rec.outputs[0].utime, 77);
  EXPECT_EQ(rec.outputs[0].event_number, static_cast<std::int64_t>(1 + 2 * evs.size()));
  EXPECT_EQ(rec.outputs[0].bytes, (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_EQ(rec.events, static_cast<std::int64_t>(3 + 2 * evs.size()));  // info, events and ticks, output, end
  EXPECT_FALSE(rec.truncated);
  EXPECT_TRUE(rec.warnings.empty());
}

TEST(HalRecordingLoader, ALogWithoutRecordingInfoIsNotARecording) {
  TempLog log("noinfo");
  write_recording(log.path(), canonical_kinds(), false);
  HalRecording rec;
  std::string err;
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("is not an rtfuse HAL recording: event 0 is on channel 'rtfuse/hal/can0'"), std::string::npos)
      << err;
}

TEST(HalRecordingLoader, AnotherFormatVersionIsRefusedWithTheFix) {
  TempLog log("version");
  RecordingInfo info = sample_info();
  info.format_version = 7;
  const auto bytes = encode_recording_info(info);
  EventLogWriter w;
  std::string err;
  ASSERT_TRUE(w.open(log.path(), &err));
  ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
  ASSERT_TRUE(w.close(&err));
  HalRecording rec;
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("event 0 on rtfuse/rec/info: recorded in HAL record format version 7, this rtfuse reads "
                     "version " + std::to_string(kHalRecordFormatVersion) +
                     ": replay it with the rtfuse version that recorded it"),
            std::string::npos)
      << err;
}

TEST(HalRecordingLoader, TruncatedLogNeedsAllowTruncated) {
  TempLog log("trunc");
  const std::vector<BusEvent> evs = canonical_kinds();
  write_recording(log.path(), evs);
  std::vector<char> bytes;
  {
    std::ifstream in(log.path(), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  bytes.resize(bytes.size() - 2);  // the end record loses its last bytes
  {
    std::ofstream out(log.path(), std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const std::int64_t complete = static_cast<std::int64_t>(2 + 2 * evs.size());
  HalRecording rec;
  std::string err;
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("truncated after event " + std::to_string(complete - 1) +
                     ", the recorder was probably killed or lost power: replay the first " +
                     std::to_string(complete) + " events with --allow-truncated"),
            std::string::npos)
      << err;

  ASSERT_TRUE(load(log.path(), &rec, &err, true)) << err;
  EXPECT_TRUE(rec.truncated);
  EXPECT_EQ(rec.events, complete);
  EXPECT_EQ(rec.outputs.size(), 1u);
  EXPECT_EQ(rec.ticks.size(), evs.size());
  ASSERT_EQ(rec.warnings.size(), 1u);
}

TEST(HalRecordingLoader, ALogCutBetweenTwoEventsNeedsAllowTruncated) {
  // A power loss after the writer flushed whole events: nothing is torn,
  // only the end record is missing.
  TempLog log("boundary");
  const std::vector<BusEvent> evs = canonical_kinds();
  write_recording(log.path(), evs, true, false);
  const std::int64_t complete = static_cast<std::int64_t>(2 + 2 * evs.size());
  HalRecording rec;
  std::string err;
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("ends after event " + std::to_string(complete - 1) +
                     ", the recorder was probably killed or lost power: replay the first " +
                     std::to_string(complete) + " events with --allow-truncated (no rtfuse/rec/end record"),
            std::string::npos)
      << err;
  ASSERT_TRUE(load(log.path(), &rec, &err, true)) << err;
  EXPECT_TRUE(rec.truncated);
  EXPECT_EQ(rec.events, complete);
  EXPECT_EQ(rec.outputs.size(), 1u);
  ASSERT_EQ(rec.warnings.size(), 1u);

  write_recording(log.path(), evs);
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  EXPECT_FALSE(rec.truncated);
  EXPECT_TRUE(rec.warnings.empty());
}

TEST(HalRecordingLoader, TheEndRecordMustBeLastAndCountTheEvents) {
  TempLog log("end");
  const RecordingInfo info = sample_info();
  const auto bytes = encode_recording_info(info);
  const std::uint8_t out[3] = {1, 2, 3};
  std::string err;
  HalRecording rec;
  {
    EventLogWriter w;
    ASSERT_TRUE(w.open(log.path(), &err)) << err;
    ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
    ASSERT_TRUE(test::write_recording_end(w, 2, &err));
    ASSERT_TRUE(w.write(3, "rtfuse/odometry", out, sizeof out, &err));
    ASSERT_TRUE(w.close(&err));
  }
  EXPECT_FALSE(load(log.path(), &rec, &err, true));
  EXPECT_NE(err.find("event 2 on channel rtfuse/odometry cannot be decoded: an event after the end of the "
                     "recording"),
            std::string::npos)
      << err;
  {
    // An event removed from the middle: the end record counts it.
    EventLogWriter w;
    ASSERT_TRUE(w.open(log.path(), &err)) << err;
    ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
    const auto end = encode_recording_end({2'000, 3, 0});
    ASSERT_TRUE(w.write(2, std::string(kRecordingEndChannel), end.data(), end.size(), &err));
    ASSERT_TRUE(w.close(&err));
  }
  EXPECT_FALSE(load(log.path(), &rec, &err, true));
  EXPECT_NE(err.find("the end record counts 3 events before it, the log holds 1"), std::string::npos) << err;
}

TEST(HalRecordingLoader, TickSeqsAtTheEdgesOfInt64AreNoOverflow) {
  // A tick seq of INT64_MAX once overflowed last_seq + 1 (issue 11, defect
  // 2); huge gaps are counted (negative seqs: HalRecordCodec.ANegativeTickSeqIsRefused).
  HalRecordCodec codec(sample_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  const std::int64_t consumed[1] = {0};
  std::string err;

  TempLog log("seq");
  const auto bytes = encode_recording_info(sample_info());
  auto write_ticks = [&](std::initializer_list<std::int64_t> seqs) {
    EventLogWriter w;
    ASSERT_TRUE(w.open(log.path(), &err)) << err;
    ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
    std::int64_t t = 2;
    for (const std::int64_t seq : seqs) {
      const int k = codec.encode_tick(t * 1000, seq, consumed, 1, 0u, buf, sizeof buf);
      ASSERT_TRUE(w.write(t++, std::string(kLoopTickChannel), buf, static_cast<std::size_t>(k), &err));
    }
    ASSERT_TRUE(test::write_recording_end(w, t, &err));
    ASSERT_TRUE(w.close(&err));
  };
  HalRecording rec;
  write_ticks({0, INT64_MAX});
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  EXPECT_EQ(rec.missing_ticks, INT64_MAX - 1);
  write_ticks({INT64_MAX, INT64_MAX});
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("tick seq 9223372036854775807 after 9223372036854775807 goes backwards"), std::string::npos)
      << err;
  write_ticks({0, INT64_MAX / 2, INT64_MAX});
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  EXPECT_EQ(rec.missing_ticks, INT64_MAX - 2);
}

TEST(HalRecordingLoader, AnUndecodableEventIsNamed) {
  TempLog log("bad");
  write_recording(log.path(), {});
  {
    EventLogWriter w;
    std::string err;
    // Rewrite with a broken hal record appended after the info.
    const auto info = encode_recording_info(sample_info());
    ASSERT_TRUE(w.open(log.path(), &err));
    ASSERT_TRUE(w.write(1, std::string(kRecordingInfoChannel), info.data(), info.size(), &err));
    const std::uint8_t junk[20] = {1, 2, 3};
    ASSERT_TRUE(w.write(2, "rtfuse/hal/i2c-1", junk, sizeof junk, &err));
    ASSERT_TRUE(w.close(&err));
  }
  HalRecording rec;
  std::string err;
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("event 1 on channel rtfuse/hal/i2c-1 cannot be decoded"), std::string::npos) << err;
}

TEST(HalRecordingLoader, AHoleEndsItsStreamOnly) {
  TempLog log("hole");
  std::vector<BusEvent> evs;
  BusEvent now;
  now.kind = BusEventKind::kClockNow;
  now.device = 4;  // imu stream
  BusEvent set;
  set.kind = BusEventKind::kGpioSet;
  set.device = 3;  // loop stream
  for (int i = 0; i < 6; ++i) {
    now.clock_ns = i;
    now.lost_before = i == 3 ? 2 : 0;
    evs.push_back(now);
    set.level = static_cast<std::uint8_t>(i & 1);
    evs.push_back(set);
  }
  write_recording(log.path(), evs);
  HalRecording rec;
  std::string err;
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  EXPECT_EQ(rec.streams[1]->size(), 3u) << "imu stops before the hole";
  EXPECT_TRUE(rec.streams[1]->has_hole());
  EXPECT_EQ(rec.streams[0]->size(), 6u) << "the loop is complete";
  EXPECT_EQ(rec.lost_events, 2);
  ASSERT_EQ(rec.warnings.size(), 1u);
  EXPECT_NE(rec.warnings[0].find("stream 'imu': the recorder lost 2 events before event 13"), std::string::npos)
      << rec.warnings[0];
}

TEST(HalRecordingLoader, CarriesTheRecordedFilesIntoTheInfo) {
  TempLog log("files");
  const RecordingInfo info = sample_info();
  EventLogWriter w;
  std::string err;
  ASSERT_TRUE(w.open(log.path(), &err)) << err;
  const auto bytes = encode_recording_info(info);
  ASSERT_TRUE(w.write(5'000'000, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
  const auto file = encode_recorded_file(calibration_file());
  ASSERT_TRUE(w.write(5'000'000, std::string(kRecordedFileChannel), file.data(), file.size(), &err));
  ASSERT_TRUE(w.write(5'000'001, std::string(kRecordedFileChannel), file.data(), file.size(), &err));
  ASSERT_TRUE(w.close(&err)) << err;
  HalRecording rec;
  // The same key twice: the second is named.
  EXPECT_FALSE(load(log.path(), &rec, &err));
  EXPECT_NE(err.find("event 2 on channel rtfuse/rec/file"), std::string::npos) << err;
  EXPECT_NE(err.find("two files for 'camera.calibration'"), std::string::npos) << err;

  ASSERT_TRUE(w.open(log.path(), &err)) << err;
  ASSERT_TRUE(w.write(5'000'000, std::string(kRecordingInfoChannel), bytes.data(), bytes.size(), &err));
  ASSERT_TRUE(w.write(5'000'000, std::string(kRecordedFileChannel), file.data(), file.size(), &err));
  ASSERT_TRUE(test::write_recording_end(w, 5'000'000, &err)) << err;
  ASSERT_TRUE(w.close(&err)) << err;
  ASSERT_TRUE(load(log.path(), &rec, &err)) << err;
  ASSERT_EQ(rec.info.files.size(), 1u);
  EXPECT_EQ(rec.info.files[0].text, calibration_file().text);
  EXPECT_TRUE(rec.outputs.empty()) << "a recorded file is not an output";
}

}  // namespace hal_recording_test
}  // namespace rtfuse
