#include "runtime/pipeline/recorder.hpp"

#include <gtest/gtest.h>

#include "support/temp_file.hpp"
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "hal/mock/mock_can_bus.hpp"
#include "hal/replay/replay_can_bus.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/recording_can_bus.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::runtime {
namespace recorder_test {

using hal::BusEvent;
using hal::BusEventKind;
using hal::HalStatus;
using transport::DeviceKind;
using transport::RecordingInfo;

// A log path of this test, removed afterwards.
class TempLog : public test::TempFile {
 public:
  explicit TempLog(const std::string& name) : TempFile("rec_" + name, ".lcm") {}
};

RecordingInfo make_info() {
  RecordingInfo info;
  info.rtfuse_version = "0.1.0";
  info.config_path = "config/sim.toml";
  info.config_text = "[loop]\nrate_hz = 200\n";
  info.streams = {"loop", "imu"};
  info.devices = {{"can0", DeviceKind::kCan, 0}, {"imu-clock", DeviceKind::kClock, 1}};
  return info;
}

bool load(const std::string& path, HalRecording* rec, std::string* err, bool allow_truncated = false) {
  transport::EventLogReader reader;
  if (!reader.open(path, err)) return false;
  HalRecordingOptions opts;
  opts.allow_truncated = allow_truncated;
  return load_hal_recording(reader, opts, rec, err);
}

BusEvent clock_now(TimeNs t) {
  BusEvent ev;
  ev.kind = BusEventKind::kClockNow;
  ev.device = 1;
  ev.time_ns = t;
  ev.clock_ns = t;
  return ev;
}

BusEvent can_receive(TimeNs t, int frames) {
  BusEvent ev;
  ev.kind = BusEventKind::kCanReceive;
  ev.device = 0;
  ev.time_ns = t;
  ev.length = 16;
  ev.count = static_cast<std::uint8_t>(frames);
  ev.status = frames > 0 ? HalStatus::kOk : HalStatus::kWouldBlock;
  ev.bus_state = hal::CanBusState::kErrorActive;
  for (int i = 0; i < frames; ++i) {
    ev.frames[i].id = 0x181 + static_cast<std::uint32_t>(i);
    ev.frames[i].dlc = 4;
    ev.frames[i].data[0] = static_cast<std::uint8_t>(t);
    ev.frames[i].stamp = t - 100 + i;
  }
  return ev;
}

TEST(Recorder, WritesALogTheLoaderReadsBackIdentically) {
  TempLog log("roundtrip");
  std::string err;
  auto rec = Recorder::create(log.path(), make_info(), {}, &err);
  ASSERT_TRUE(rec) << err;
  ASSERT_EQ(rec->stream_count(), 2);
  EXPECT_EQ(rec->stream_index("imu"), 1);
  ASSERT_TRUE(rec->start(&err)) << err;

  std::vector<BusEvent> loop_events, imu_events;
  std::vector<std::vector<std::uint8_t>> outputs;
  for (int i = 0; i < 300; ++i) {
    const TimeNs t = TimeNs{1'000'000'000} + TimeNs{i} * 5'000'000;
    const BusEvent rx = can_receive(t, i % 5);
    const BusEvent now = clock_now(t + 1);
    // A full ring loses the event; the test then waits like a producer would not.
    while (!rec->ring(0).try_push(rx)) std::this_thread::yield();
    while (!rec->ring(1).try_push(now)) std::this_thread::yield();
    loop_events.push_back(rx);
    imu_events.push_back(now);
    const std::int64_t consumed[3] = {i, 2 * i, 0};
    while (!rec->record_tick(t, static_cast<std::uint64_t>(i), consumed, 3)) std::this_thread::yield();
    if (i % 10 == 0) {
      std::vector<std::uint8_t> msg(100 + static_cast<std::size_t>(i), static_cast<std::uint8_t>(i));
      while (!rec->record_output("rtfuse/odometry", msg.data(), static_cast<int>(msg.size()), t)) {
        std::this_thread::yield();
      }
      outputs.push_back(msg);
    }
  }
  ASSERT_TRUE(rec->stop(&err)) << err;
  const RecorderStats stats = rec->stats();
  EXPECT_EQ(stats.events_written, 1 + 300 + 300 + 300 + 30 + 1);  // info ... end record
  EXPECT_EQ(stats.write_errors, 0);
  EXPECT_EQ(stats.encode_errors, 0);
  EXPECT_EQ(stats.bus_events_lost, (std::vector<std::int64_t>{0, 0}));

  HalRecording loaded;
  ASSERT_TRUE(load(log.path(), &loaded, &err)) << err;
  EXPECT_FALSE(loaded.truncated) << "stop() ends the log with its end record";
  EXPECT_EQ(loaded.info.config_text, "[loop]\nrate_hz = 200\n");
  EXPECT_EQ(loaded.info.config_hash, transport::config_text_hash("[loop]\nrate_hz = 200\n"));
  EXPECT_GT(loaded.info.start_ns, 0);
  ASSERT_EQ(loaded.streams.size(), 2u);
  ASSERT_EQ(loaded.streams[0]->size(), loop_events.size());
  ASSERT_EQ(loaded.streams[1]->size(), imu_events.size());
  for (std::size_t i = 0; i < loop_events.size(); ++i) {
    ASSERT_EQ(loaded.streams[0]->event(i), loop_events[i]) << i;
    ASSERT_EQ(loaded.streams[1]->event(i), imu_events[i]) << i;
  }
  ASSERT_EQ(loaded.ticks.size(), 300u);
  EXPECT_EQ(loaded.ticks[299].seq, 299);
  EXPECT_EQ(loaded.ticks[299].time_ns, TimeNs{1'000'000'000} + 299 * TimeNs{5'000'000});
  EXPECT_EQ(loaded.ticks[299].consumed, (std::vector<std::int64_t>{299, 598, 0}));
  ASSERT_EQ(loaded.outputs.size(), outputs.size());
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    EXPECT_EQ(loaded.outputs[i].channel, "rtfuse/odometry");
    EXPECT_EQ(loaded.outputs[i].bytes, outputs[i]);
  }
  EXPECT_EQ(loaded.outputs[1].utime, (1'000'000'000 + 10 * 5'000'000) / 1000);
  EXPECT_EQ(loaded.missing_ticks, 0);
  EXPECT_TRUE(loaded.warnings.empty());
}

TEST(Recorder, ProducerCallsDoNotAllocateAndFullRingsAreCounted) {
  TempLog log("alloc");
  std::string err;
  RecorderRingSizes sizes;
  sizes.ticks = 4;
  sizes.outputs = 2;
  auto rec = Recorder::create(log.path(), make_info(), sizes, &err);
  ASSERT_TRUE(rec) << err;
  const std::int64_t consumed[2] = {1, 2};
  const std::uint8_t msg[64] = {};
  std::vector<std::uint8_t> huge(Recorder::kMaxOutputBytes + 1);
  {
    test::AllocScope scope;
    for (int i = 0; i < 6; ++i) rec->record_tick(i, static_cast<std::uint64_t>(i), consumed, 2);
    for (int i = 0; i < 3; ++i) rec->record_output("rtfuse/pose", msg, sizeof msg, i);
    EXPECT_FALSE(rec->record_output("rtfuse/state", huge.data(), static_cast<int>(huge.size()), 0));
    EXPECT_FALSE(rec->record_output("", msg, sizeof msg, 0));
    EXPECT_FALSE(rec->record_tick(0, 0, consumed, Recorder::kMaxTickSensors + 1));
    EXPECT_EQ(scope.count(), 0u);
  }
  RecorderStats s = rec->stats();
  EXPECT_EQ(s.ticks_lost, 2);
  EXPECT_EQ(s.ticks_rejected, 1);
  EXPECT_EQ(s.outputs_lost, 1);
  EXPECT_EQ(s.outputs_rejected, 2);
  // Never started: stop() still writes what was queued.
  ASSERT_TRUE(rec->stop(&err)) << err;
  s = rec->stats();
  EXPECT_EQ(s.events_written, 1 + 4 + 2 + 1);  // info, ticks, outputs, end record
  HalRecording loaded;
  ASSERT_TRUE(load(log.path(), &loaded, &err)) << err;
  EXPECT_EQ(loaded.ticks.size(), 4u);
  EXPECT_EQ(loaded.outputs.size(), 2u);
}

TEST(Recorder, DecoratorsRecordAndTheRecordingReplays) {
  TempLog log("decorated");
  std::string err;
  auto rec = Recorder::create(log.path(), make_info(), {}, &err);
  ASSERT_TRUE(rec) << err;
  ASSERT_TRUE(rec->start(&err)) << err;
  hal::mock::SimClock clock(1'000);
  hal::mock::MockCanBus can({}, &clock);
  hal::RecordingCanBus rcan(can, rec->ring(0), 0, &clock);
  hal::CanFrame sync;
  sync.id = 0x080;
  hal::CanFrame tpdo;
  tpdo.id = 0x181;
  tpdo.dlc = 2;
  tpdo.data[1] = 0x42;
  can.inject(tpdo);
  hal::CanFrame out[4];
  HalStatus st;
  {
    test::AllocScope scope;
    EXPECT_EQ(rcan.send(sync), HalStatus::kOk);
    EXPECT_EQ(rcan.receive(out, 4, 0, &st), 1);
    EXPECT_EQ(rcan.receive(out, 4, 0, &st), 0);
    EXPECT_EQ(scope.count(), 0u);
  }
  ASSERT_TRUE(rec->stop(&err)) << err;

  HalRecording loaded;
  ASSERT_TRUE(load(log.path(), &loaded, &err)) << err;
  hal::replay::ReplayCanBus replay(*loaded.streams[0], 0);
  EXPECT_EQ(replay.send(sync), HalStatus::kOk);
  ASSERT_EQ(replay.receive(out, 4, 0, &st), 1);
  EXPECT_EQ(out[0].id, 0x181u);
  EXPECT_EQ(out[0].data[1], 0x42);
  EXPECT_EQ(out[0].stamp, 1'000);
  EXPECT_EQ(replay.receive(out, 4, 0, &st), 0);
  EXPECT_EQ(st, HalStatus::kWouldBlock);
  EXPECT_TRUE(loaded.streams[0]->at_end());
  EXPECT_FALSE(loaded.streams[0]->diverged());
}

TEST(Recorder, ACutFileLoadsOnlyWithAllowTruncated) {
  TempLog log("cut");
  std::string err;
  {
    auto rec = Recorder::create(log.path(), make_info(), {}, &err);
    ASSERT_TRUE(rec) << err;
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(rec->ring(1).try_push(clock_now(i + 1)));
    ASSERT_TRUE(rec->stop(&err)) << err;
  }
  std::vector<char> bytes;
  {
    std::ifstream in(log.path(), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // Events 0 (info) .. 10 (the last clock read), 11 the end record; cut
  // inside the end record.
  bytes.resize(bytes.size() - 5);
  {
    std::ofstream out(log.path(), std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  HalRecording loaded;
  EXPECT_FALSE(load(log.path(), &loaded, &err));
  EXPECT_NE(err.find("truncated after event 10, the recorder was probably killed or lost power: replay the first 11 "
                     "events with --allow-truncated"),
            std::string::npos)
      << err;
  ASSERT_TRUE(load(log.path(), &loaded, &err, true)) << err;
  EXPECT_TRUE(loaded.truncated);
  EXPECT_EQ(loaded.streams[1]->size(), 10u);
  EXPECT_EQ(loaded.streams[1]->event(9).clock_ns, 10);
}

TEST(Recorder, ALostEventShowsAsAHoleInTheLoadedStream) {
  TempLog log("hole");
  std::string err;
  RecorderRingSizes sizes;
  sizes.bus_events = 2;
  auto rec = Recorder::create(log.path(), make_info(), sizes, &err);
  ASSERT_TRUE(rec) << err;
  hal::mock::SimClock clock(0);
  hal::mock::MockCanBus can({}, &clock);
  hal::RecordingCanBus rcan(can, rec->ring(0), 0, &clock);
  hal::CanFrame f;
  for (int i = 0; i < 3; ++i) rcan.send(f);  // the third finds the ring full
  EXPECT_EQ(rcan.overflows(), 1);
  ASSERT_TRUE(rec->start(&err)) << err;
  while (rec->stats().events_written < 3) std::this_thread::yield();
  rcan.send(f);  // carries lost_before = 1
  ASSERT_TRUE(rec->stop(&err)) << err;
  EXPECT_EQ(rec->stats().bus_events_lost, (std::vector<std::int64_t>{1, 0}));
  HalRecording loaded;
  ASSERT_TRUE(load(log.path(), &loaded, &err)) << err;
  EXPECT_EQ(loaded.streams[0]->size(), 2u);
  EXPECT_EQ(loaded.lost_events, 1);
  hal::replay::ReplayCanBus replay(*loaded.streams[0], 0);
  EXPECT_EQ(replay.send(f), HalStatus::kOk);
  EXPECT_EQ(replay.send(f), HalStatus::kOk);
  EXPECT_EQ(replay.send(f), HalStatus::kClosed);
  EXPECT_NE(std::string(loaded.streams[0]->divergence()).find("where the recorder lost 1 events"), std::string::npos)
      << loaded.streams[0]->divergence();
}

TEST(Recorder, RefusesAnInvalidDeviceTableAndAnUnwritablePath) {
  std::string err;
  RecordingInfo info = make_info();
  info.devices.push_back({"can0", DeviceKind::kCan, 0});
  EXPECT_FALSE(Recorder::create(testing::TempDir() + "rtfuse_rec_never.lcm", info, {}, &err));
  EXPECT_NE(err.find("the name is also device 0's"), std::string::npos) << err;
  EXPECT_FALSE(Recorder::create("/nonexistent-dir/x.lcm", make_info(), {}, &err));
  EXPECT_NE(err.find("cannot create log file /nonexistent-dir/x.lcm"), std::string::npos) << err;
}

}  // namespace recorder_test
}  // namespace rtfuse::runtime
