#include "transport/hal_record_codec.hpp"

#include <gtest/gtest.h>

#include "support/recording_end.hpp"
#include "support/temp_file.hpp"
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "rtfuse/hal_can_t.hpp"
#include "rtfuse/hal_serial_t.hpp"
#include "rtfuse/recording_info_t.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::transport {
namespace {

using hal::BusEvent;
using hal::BusEventKind;
using hal::CanBusState;
using hal::HalStatus;

// A log path of this test, removed afterwards.
class TempLog : public test::TempFile {
 public:
  explicit TempLog(const std::string& name) : TempFile("codec_" + name, ".lcm") {}
};

RecordingInfo make_info() {
  RecordingInfo info;
  info.start_ns = 5'000'000'000;
  info.rtfuse_version = "0.1.0";
  info.config_path = "config/robot.toml";
  info.config_text = "[loop]\nrate_hz = 200\n";
  info.config_hash = config_text_hash(info.config_text);
  info.streams = {"loop", "imu"};
  info.devices = {{"can0", DeviceKind::kCan, 0},
                  {"i2c-1", DeviceKind::kI2c, 1},
                  {"imu-drdy", DeviceKind::kGpioEdge, 1},
                  {"led", DeviceKind::kGpioOutput, 0},
                  {"imu-clock", DeviceKind::kClock, 1},
                  {"gnss0", DeviceKind::kSerial, 0}};
  return info;
}

// One canonical event of every kind, with values that exercise the ranges.
std::vector<BusEvent> every_kind() {
  std::vector<BusEvent> evs;
  BusEvent send;
  send.kind = BusEventKind::kCanSend;
  send.device = 0;
  send.time_ns = 1'234'567'891;
  send.status = HalStatus::kBusError;
  send.bus_state = CanBusState::kErrorPassive;
  send.count = 1;
  send.frames[0].id = 0x1ABCDEF0;
  send.frames[0].extended = true;
  send.frames[0].dlc = 8;
  for (int i = 0; i < 8; ++i) send.frames[0].data[i] = static_cast<std::uint8_t>(0xF0 + i);
  send.lost_before = 0xFFFFFFFFu;  // survives the int32 field
  evs.push_back(send);

  BusEvent rx;
  rx.kind = BusEventKind::kCanReceive;
  rx.device = 0;
  rx.time_ns = 2'000'000'000;
  rx.timeout_ns = 5'000'000;
  rx.length = 16;
  rx.count = 16;
  rx.bus_state = CanBusState::kBusOff;
  for (int i = 0; i < 16; ++i) {
    rx.frames[i].id = 0x181 + static_cast<std::uint32_t>(i);
    rx.frames[i].dlc = static_cast<std::uint8_t>(i % 9);
    rx.frames[i].rtr = i == 3;
    rx.frames[i].error = i == 4;
    rx.frames[i].stamp = 1'999'000'000 + i;
    for (int b = 0; b < 8; ++b) rx.frames[i].data[b] = static_cast<std::uint8_t>(i * 8 + b);
  }
  evs.push_back(rx);

  BusEvent rd;
  rd.kind = BusEventKind::kI2cRead;
  rd.device = 1;
  rd.time_ns = -5;  // time before the epoch of the clock still round-trips
  rd.address = 0x68;
  rd.reg = 0xFF;
  rd.length = 64;
  rd.retries = 123'456'789'012;
  for (int i = 0; i < 64; ++i) rd.data[i] = static_cast<std::uint8_t>(255 - i);
  evs.push_back(rd);

  BusEvent nack = rd;
  nack.status = HalStatus::kNack;
  for (auto& b : nack.data) b = 0;
  nack.length = 14;
  evs.push_back(nack);

  BusEvent wr;
  wr.kind = BusEventKind::kI2cWrite;
  wr.device = 1;
  wr.address = 0x77;
  wr.reg = 0x6B;
  wr.length = 1;
  wr.value = 0x80;
  evs.push_back(wr);

  BusEvent edge;
  edge.kind = BusEventKind::kGpioWaitEdge;
  edge.device = 2;
  edge.timeout_ns = 10'000'000;
  edge.edge_stamp = 3'000'000'001;
  edge.level = 1;
  evs.push_back(edge);

  BusEvent timeout = edge;
  timeout.status = HalStatus::kTimeout;
  timeout.edge_stamp = 0;
  timeout.level = 0;
  evs.push_back(timeout);

  BusEvent set;
  set.kind = BusEventKind::kGpioSet;
  set.device = 3;
  set.level = 1;
  set.status = HalStatus::kIoError;
  evs.push_back(set);

  BusEvent now;
  now.kind = BusEventKind::kClockNow;
  now.device = 4;
  now.time_ns = 4'000'000'123;
  now.clock_ns = 4'000'000'123;
  evs.push_back(now);

  BusEvent sleep;
  sleep.kind = BusEventKind::kClockSleepUntil;
  sleep.device = 4;
  sleep.time_ns = 4'000'000'200;
  sleep.clock_ns = 4'005'000'000;
  evs.push_back(sleep);

  BusEvent read;
  read.kind = BusEventKind::kSerialRead;
  read.device = 5;
  read.time_ns = 5'000'000'000;
  read.timeout_ns = 50'000'000;
  read.length = 64;
  read.count = 64;
  read.edge_stamp = 4'999'999'000;
  for (int i = 0; i < 64; ++i) read.data[i] = static_cast<std::uint8_t>(0xB5 + i);
  evs.push_back(read);

  BusEvent quiet;
  quiet.kind = BusEventKind::kSerialRead;
  quiet.device = 5;
  quiet.timeout_ns = 50'000'000;
  quiet.length = 64;
  quiet.status = HalStatus::kTimeout;
  evs.push_back(quiet);

  BusEvent command;
  command.kind = BusEventKind::kSerialWrite;
  command.device = 5;
  command.length = 3;
  command.data[0] = 0xB5;
  command.data[1] = 0x62;
  command.data[2] = 0x06;
  evs.push_back(command);

  BusEvent reopen;
  reopen.kind = BusEventKind::kSerialReopen;
  reopen.device = 5;
  reopen.time_ns = 6'000'000'000;
  reopen.status = HalStatus::kClosed;
  evs.push_back(reopen);
  return evs;
}

TEST(HalRecordCodec, EveryKindRoundTripsByteForByte) {
  HalRecordCodec codec(make_info().devices);
  for (const BusEvent& ev : every_kind()) {
    std::uint8_t buf[kMaxHalRecordSize];
    const int n = codec.encode(ev, buf, sizeof buf);
    ASSERT_GT(n, 0) << to_string(ev.kind);
    BusEvent back;
    std::string err;
    ASSERT_TRUE(codec.decode(codec.channel(ev.device), buf, n, &back, &err)) << to_string(ev.kind) << ": " << err;
    EXPECT_EQ(back, ev) << to_string(ev.kind);
  }
}

TEST(HalRecordCodec, ChannelsAreNamedAfterTheDevices) {
  HalRecordCodec codec(make_info().devices);
  EXPECT_EQ(codec.channel(0), "rtfuse/hal/can0");
  EXPECT_EQ(codec.channel(1), "rtfuse/hal/i2c-1");
  EXPECT_EQ(codec.channel(4), "rtfuse/hal/imu-clock");
  EXPECT_EQ(codec.channel(5), "rtfuse/hal/gnss0");
  EXPECT_EQ(codec.channel(6), "");
  EXPECT_EQ(codec.device_of("rtfuse/hal/imu-drdy"), 2);
  EXPECT_EQ(codec.device_of("rtfuse/hal/can1"), -1);
}

TEST(HalRecordCodec, EncodeRefusesWhatTheTableDoesNotList) {
  HalRecordCodec codec(make_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  BusEvent ev = every_kind()[0];  // a CAN send
  ev.device = 9;
  EXPECT_EQ(codec.encode(ev, buf, sizeof buf), -1);
  ev.device = 1;  // an I2C bus
  EXPECT_EQ(codec.encode(ev, buf, sizeof buf), -1);
  ev.device = 0;
  EXPECT_EQ(codec.encode(ev, buf, 10), -1) << "does not fit";
  EXPECT_GT(codec.encode(ev, buf, sizeof buf), 0);
}

TEST(HalRecordCodec, DecodeNamesWhatIsWrong) {
  HalRecordCodec codec(make_info().devices);
  const std::vector<BusEvent> evs = every_kind();
  std::uint8_t buf[kMaxHalRecordSize];
  const int n_i2c = codec.encode(evs[2], buf, sizeof buf);
  BusEvent out;
  std::string err;
  EXPECT_FALSE(codec.decode("rtfuse/hal/can0", buf, n_i2c, &out, &err));
  EXPECT_NE(err.find("not a hal_can_t"), std::string::npos) << err;
  EXPECT_FALSE(codec.decode("rtfuse/hal/nope", buf, n_i2c, &out, &err));
  EXPECT_NE(err.find("names no device"), std::string::npos) << err;
  EXPECT_FALSE(codec.decode("rtfuse/hal/i2c-1", buf, n_i2c - 3, &out, &err));
  EXPECT_NE(err.find("malformed hal_i2c_t"), std::string::npos) << err;
  EXPECT_FALSE(codec.decode("rtfuse/hal/i2c-1", buf, 12, &out, &err));

  // A status outside HalStatus.
  rtfuse::hal_can_t m;
  m.device = "can0";
  m.call = rtfuse::hal_can_t::RECEIVE;
  m.status = 42;
  m.num_frames = 0;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  EXPECT_FALSE(codec.decode("rtfuse/hal/can0", bytes.data(), static_cast<int>(bytes.size()), &out, &err));
  EXPECT_NE(err.find("impossible status 42"), std::string::npos) << err;

  // A record naming another device than its channel's.
  m.status = 0;
  m.device = "can9";
  bytes.assign(static_cast<std::size_t>(m.getEncodedSize()), 0);
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  EXPECT_FALSE(codec.decode("rtfuse/hal/can0", bytes.data(), static_cast<int>(bytes.size()), &out, &err));
  EXPECT_NE(err.find("names device 'can9'"), std::string::npos) << err;
}

TEST(HalRecordCodec, ImpossibleSerialRecordsAreNamed) {
  HalRecordCodec codec(make_info().devices);
  BusEvent out;
  std::string err;
  const auto decode = [&](const rtfuse::hal_serial_t& m) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    return codec.decode("rtfuse/hal/gnss0", bytes.data(), static_cast<int>(bytes.size()), &out, &err);
  };
  rtfuse::hal_serial_t m{};  // lcm-gen leaves scalars uninitialised
  m.device = "gnss0";
  m.call = rtfuse::hal_serial_t::READ;
  m.length = 8;
  m.num_data = 4;
  m.data = {1, 2, 3, 4};
  m.stamp_ns = 77;
  ASSERT_TRUE(decode(m)) << err;
  EXPECT_EQ(out.count, 4);
  EXPECT_EQ(out.edge_stamp, 77);
  m.length = 2;  // more bytes than asked for
  EXPECT_FALSE(decode(m));
  EXPECT_NE(err.find("impossible data byte count 4"), std::string::npos) << err;
  m.length = 65;
  EXPECT_FALSE(decode(m));
  EXPECT_NE(err.find("impossible length 65"), std::string::npos) << err;
  m.length = 8;
  m.call = rtfuse::hal_serial_t::WRITE;  // a write of 8 bytes holding 4
  EXPECT_FALSE(decode(m));
  EXPECT_NE(err.find("data byte count"), std::string::npos) << err;
  m.length = 4;
  EXPECT_FALSE(decode(m));  // a stamp on a write
  EXPECT_NE(err.find("stamp_ns"), std::string::npos) << err;
  m.stamp_ns = 0;
  m.timeout_ns = 5;
  EXPECT_FALSE(decode(m));
  EXPECT_NE(err.find("timeout_ns of a write"), std::string::npos) << err;
  m.timeout_ns = 0;
  ASSERT_TRUE(decode(m)) << err;
  EXPECT_EQ(out.kind, BusEventKind::kSerialWrite);
  m.call = 5;
  EXPECT_FALSE(decode(m));
  EXPECT_NE(err.find("impossible call 5"), std::string::npos) << err;
}

TEST(HalRecordCodec, AHugeFrameCountIsRefusedBeforeAnythingIsReserved) {
  HalRecordCodec codec(make_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  const int n = codec.encode(every_kind()[1], buf, sizeof buf);  // 16 frames
  // num_frames sits after fingerprint, utime, time_ns, "can0\0" and 19 bytes.
  const int at = 8 + 8 + 8 + 4 + 5 + 19;
  ASSERT_EQ(buf[at + 3], 16);
  buf[at] = 0x40;  // 1'073'741'840 frames
  BusEvent out;
  std::string err;
  const std::uint64_t before = rtfuse::test::allocation_count();
  EXPECT_FALSE(codec.decode("rtfuse/hal/can0", buf, n, &out, &err));
  EXPECT_NE(err.find("more than 16 frames"), std::string::npos) << err;
  EXPECT_LT(rtfuse::test::allocation_count() - before, 4u) << "only the error text";
}

TEST(HalRecordCodec, EncodingStopsAllocatingOnceWarm) {
  HalRecordCodec codec(make_info().devices);
  const std::vector<BusEvent> evs = every_kind();
  std::uint8_t buf[kMaxHalRecordSize];
  for (const BusEvent& ev : evs) ASSERT_GT(codec.encode(ev, buf, sizeof buf), 0);
  const std::int64_t consumed[3] = {1, 2, 3};
  ASSERT_GT(codec.encode_tick(1, 1, consumed, 3, 0u, buf, sizeof buf), 0);
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 3; ++i) {
    for (const BusEvent& ev : evs) codec.encode(ev, buf, sizeof buf);
    codec.encode_tick(2, 2, consumed, 3, 0u, buf, sizeof buf);
  }
  EXPECT_EQ(scope.count(), 0u);
}

TEST(HalRecordCodec, TicksRoundTrip) {
  HalRecordCodec codec({});
  const std::int64_t consumed[4] = {10, 0, 7, 123'456'789'012};
  std::uint8_t buf[kMaxHalRecordSize];
  const int n = codec.encode_tick(9'000'000'005, 77, consumed, 4, 0x25u, buf, sizeof buf);
  ASSERT_GT(n, 0);
  LoopTick tick;
  std::string err;
  ASSERT_TRUE(HalRecordCodec::decode_tick(buf, n, &tick, &err)) << err;
  EXPECT_EQ(tick.time_ns, 9'000'000'005);
  EXPECT_EQ(tick.seq, 77);
  EXPECT_EQ(tick.consumed, (std::vector<std::int64_t>{10, 0, 7, 123'456'789'012}));
  EXPECT_EQ(tick.published, 0x25u);
  EXPECT_EQ(codec.encode_tick(0, 0, consumed, kMaxTickSensors + 1, 0u, buf, sizeof buf), -1);
}

TEST(HalRecordingInfo, RoundTripsAndChecksTheVersion) {
  const RecordingInfo info = make_info();
  const std::vector<std::uint8_t> bytes = encode_recording_info(info);
  RecordingInfo back;
  std::string err;
  ASSERT_TRUE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err)) << err;
  EXPECT_EQ(back.format_version, kHalRecordFormatVersion);
  EXPECT_EQ(back.start_ns, info.start_ns);
  EXPECT_EQ(back.rtfuse_version, "0.1.0");
  EXPECT_EQ(back.config_path, info.config_path);
  EXPECT_EQ(back.config_text, info.config_text);
  EXPECT_EQ(back.config_hash, config_text_hash("[loop]\nrate_hz = 200\n"));
  EXPECT_EQ(back.streams, info.streams);
  ASSERT_EQ(back.devices.size(), 6u);
  EXPECT_EQ(back.devices[5].kind, DeviceKind::kSerial);
  EXPECT_EQ(back.devices[2].name, "imu-drdy");
  EXPECT_EQ(back.devices[2].kind, DeviceKind::kGpioEdge);
  EXPECT_EQ(back.devices[2].stream, 1);

  RecordingInfo newer_info = info;
  newer_info.format_version = kHalRecordFormatVersion + 1;
  const std::vector<std::uint8_t> newer = encode_recording_info(newer_info);
  EXPECT_FALSE(decode_recording_info(newer.data(), static_cast<int>(newer.size()), &back, &err));
  const std::string expected = "format version " + std::to_string(kHalRecordFormatVersion + 1) +
                               ", this rtfuse reads version " + std::to_string(kHalRecordFormatVersion);
  EXPECT_NE(err.find(expected), std::string::npos) << err;
}

TEST(HalRecordingInfo, ValidationNamesTheBadDevice) {
  std::string err;
  RecordingInfo info = make_info();
  EXPECT_TRUE(validate(info, &err)) << err;
  info.devices[3].name = "can0";
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("device 3 'can0': the name is also device 0's"), std::string::npos) << err;
  info = make_info();
  info.devices[1].stream = 2;
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("stream 2 does not exist"), std::string::npos) << err;
  info = make_info();
  info.devices[0].name = "can/0";
  EXPECT_FALSE(validate(info, &err));
  info = make_info();
  info.streams.clear();
  EXPECT_FALSE(validate(info, &err));
}

// --- the loader -------------------------------------------------------------

void write_recording(const std::string& path, const std::vector<BusEvent>& evs, bool with_info = true,
                     bool with_end = true) {
  const RecordingInfo info = make_info();
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
  EXPECT_EQ(rec.info.streams, make_info().streams);
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
  RecordingInfo info = make_info();
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
  const RecordingInfo info = make_info();
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
  RecordingEnd end;
  const auto negative = encode_recording_end({2'000, 1, -4});
  EXPECT_FALSE(decode_recording_end(negative.data(), static_cast<int>(negative.size()), &end, &err));
  EXPECT_NE(err.find("impossible lost event count -4"), std::string::npos) << err;
}

// Writes the int32 at byte `at` of an encoded record (LCM is big-endian).
void poke_i32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

TEST(HalRecordingInfo, ImpossibleStringLengthsAreRefusedBeforeDecoding) {
  // lcm-gen's decoder copies len - 1 bytes for any length: 2^31 read 2 GiB
  // past the record (issue 11, defect 1).
  const std::vector<std::uint8_t> good = encode_recording_info(make_info());
  RecordingInfo back;
  std::string err;
  const std::size_t version_at = 36;  // after the fixed fields and both counts
  for (const std::uint32_t len : {0x80000000u, 0x7fffffffu, 0u, 0xffffffffu, 4096u}) {
    std::vector<std::uint8_t> bad = good;
    poke_i32(bad, version_at, len);
    EXPECT_FALSE(decode_recording_info(bad.data(), static_cast<int>(bad.size()), &back, &err)) << len;
    EXPECT_NE(err.find("malformed recording_info_t: a string"), std::string::npos) << err;
  }
  // The last device name's length, the furthest string from the start.
  std::size_t at = version_at;
  const RecordingInfo info = make_info();
  std::vector<std::string> strings = {info.rtfuse_version, info.config_path, info.config_text};
  strings.insert(strings.end(), info.streams.begin(), info.streams.end());
  for (std::size_t i = 0; i + 1 < info.devices.size(); ++i) strings.push_back(info.devices[i].name);
  for (const std::string& str : strings) at += 4 + str.size() + 1;
  std::vector<std::uint8_t> bad = good;
  poke_i32(bad, at, 0x80000000u);
  EXPECT_FALSE(decode_recording_info(bad.data(), static_cast<int>(bad.size()), &back, &err));
  poke_i32(bad, at, static_cast<std::uint32_t>(info.devices.back().name.size() + 1));
  EXPECT_TRUE(decode_recording_info(bad.data(), static_cast<int>(bad.size()), &back, &err)) << err;
}

TEST(HalRecordingInfo, AStartTimeBeyondNanosecondsIsRefused) {
  RecordingInfo info = make_info();
  std::vector<std::uint8_t> bytes = encode_recording_info(info);
  for (int i = 0; i < 8; ++i) bytes[8 + static_cast<std::size_t>(i)] = i == 0 ? 0x7f : 0xff;  // utime INT64_MAX
  RecordingInfo back;
  std::string err;
  EXPECT_FALSE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err));
  EXPECT_NE(err.find("start time 9223372036854775807 us is beyond what nanoseconds can hold"), std::string::npos)
      << err;
}

TEST(HalRecordingLoader, TickSeqsAtTheEdgesOfInt64AreNoOverflow) {
  // A tick seq of INT64_MAX once overflowed last_seq + 1 (issue 11, defect
  // 2); negative seqs are refused, huge gaps are counted.
  HalRecordCodec codec(make_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  const std::int64_t consumed[1] = {0};
  LoopTick tick;
  std::string err;
  int n = codec.encode_tick(0, -1, consumed, 1, 0u, buf, sizeof buf);
  EXPECT_FALSE(HalRecordCodec::decode_tick(buf, n, &tick, &err));
  EXPECT_NE(err.find("negative tick seq -1"), std::string::npos) << err;

  TempLog log("seq");
  const auto bytes = encode_recording_info(make_info());
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
    const auto info = encode_recording_info(make_info());
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

}  // namespace
}  // namespace rtfuse::transport

// --- files the configuration names (recording_file_t) ------------------------

namespace rtfuse::transport {
namespace {

RecordedFile calibration_file() {
  // A NUL and a byte above 127 among the text; the length from the array
  // itself (a hand-counted 36 read past its 30 bytes: found by ASan).
  static constexpr char kText[] = "[LEFT_CAM_VGA]\nfx=350\n\0binary\xff";
  return {"camera.calibration", "/etc/rtfuse/calibration/SN10000001.conf", std::string(kText, sizeof kText - 1)};
}

TEST(HalRecordedFile, RoundTripsEveryByte) {
  const RecordedFile f = calibration_file();
  const std::vector<std::uint8_t> bytes = encode_recorded_file(f);
  RecordedFile back;
  std::string err;
  ASSERT_TRUE(decode_recorded_file(bytes.data(), static_cast<int>(bytes.size()), &back, &err)) << err;
  EXPECT_EQ(back.key, f.key);
  EXPECT_EQ(back.path, f.path);
  EXPECT_EQ(back.text, f.text);
}

TEST(HalRecordedFile, CorruptLengthsAreRefusedBeforeDecoding) {
  const std::vector<std::uint8_t> good = encode_recorded_file(calibration_file());
  std::string err;
  RecordedFile out;
  // The key's length field (after the 8-byte fingerprint) set to 0x80000000,
  // 0 and one past the end; then the byte count to -1 and to 2 GiB.
  for (const std::uint32_t len : {0x80000000u, 0u, static_cast<std::uint32_t>(good.size())}) {
    std::vector<std::uint8_t> bad = good;
    for (int i = 0; i < 4; ++i) bad[8 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(len >> (24 - 8 * i));
    EXPECT_FALSE(decode_recorded_file(bad.data(), static_cast<int>(bad.size()), &out, &err)) << len;
    EXPECT_NE(err.find("recording_file_t"), std::string::npos) << err;
  }
  const std::size_t count_at = 8 + 4 + calibration_file().key.size() + 1 + 4 + calibration_file().path.size() + 1;
  for (const std::uint32_t n : {0xffffffffu, 0x7fffffffu}) {
    std::vector<std::uint8_t> bad = good;
    for (int i = 0; i < 4; ++i) bad[count_at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
    EXPECT_FALSE(decode_recorded_file(bad.data(), static_cast<int>(bad.size()), &out, &err)) << n;
  }
  EXPECT_FALSE(decode_recorded_file(good.data(), static_cast<int>(good.size()) - 1, &out, &err));
  EXPECT_FALSE(decode_recorded_file(good.data(), 6, &out, &err));
}

TEST(HalRecordedFile, AStringWithANulInsideIsRefused) {
  // The fuzzer's finding: a path with NULs inside decoded, but lcm-gen's
  // encoder measures strings with strlen(), so the record written back from
  // it announced more bytes than it held and was refused as "8 trailing bytes".
  const std::vector<std::uint8_t> good = encode_recorded_file(calibration_file());
  const std::size_t path_at = 8 + 4 + calibration_file().key.size() + 1 + 4;
  std::vector<std::uint8_t> bad = good;
  bad[path_at + 1] = 0;
  RecordedFile out;
  std::string err;
  EXPECT_FALSE(decode_recorded_file(bad.data(), static_cast<int>(bad.size()), &out, &err));
  EXPECT_NE(err.find("NUL inside"), std::string::npos) << err;
  bad = good;
  bad[path_at + calibration_file().path.size()] = '/';  // no terminating NUL
  EXPECT_FALSE(decode_recorded_file(bad.data(), static_cast<int>(bad.size()), &out, &err));

  RecordingInfo info = make_info();
  info.config_text = std::string("a = 1\0b = 2", 11);
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("configuration text has a NUL byte at offset 5"), std::string::npos) << err;
  // What the recorder would have written from it: unreadable.
  const std::vector<std::uint8_t> bytes = encode_recording_info(info);
  RecordingInfo back;
  EXPECT_FALSE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err));
}

TEST(HalRecordedFile, LimitsAndDuplicatesAreRefused) {
  RecordingInfo info = make_info();
  std::string err;
  info.files = {calibration_file()};
  EXPECT_TRUE(validate(info, &err)) << err;
  info.files.push_back(calibration_file());
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("two files for 'camera.calibration'"), std::string::npos) << err;
  info.files = {calibration_file()};
  info.files[0].text.assign(kMaxRecordedFileBytes + 1, 'x');
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("bytes (at most"), std::string::npos) << err;
  info.files[0] = calibration_file();
  info.files[0].key.clear();
  EXPECT_FALSE(validate(info, &err));
}

TEST(HalRecordingLoader, CarriesTheRecordedFilesIntoTheInfo) {
  TempLog log("files");
  const RecordingInfo info = make_info();
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

}  // namespace
}  // namespace rtfuse::transport
