#include "transport/hal_record_codec.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "rtfuse/hal_can_t.hpp"
#include "rtfuse/hal_serial_t.hpp"
#include "rtfuse/recording_info_t.hpp"
#include "support/alloc_counter.hpp"
#include "support/hal_record_samples.hpp"

namespace rtfuse::transport {
namespace {

using hal::BusEvent;
using hal::BusEventKind;
using hal::CanBusState;
using hal::HalStatus;
using test::every_kind;
using test::sample_info;

TEST(HalRecordCodec, EveryKindRoundTripsByteForByte) {
  HalRecordCodec codec(sample_info().devices);
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
  HalRecordCodec codec(sample_info().devices);
  EXPECT_EQ(codec.channel(0), "rtfuse/hal/can0");
  EXPECT_EQ(codec.channel(1), "rtfuse/hal/i2c-1");
  EXPECT_EQ(codec.channel(4), "rtfuse/hal/imu-clock");
  EXPECT_EQ(codec.channel(5), "rtfuse/hal/gnss0");
  EXPECT_EQ(codec.channel(6), "");
  EXPECT_EQ(codec.device_of("rtfuse/hal/imu-drdy"), 2);
  EXPECT_EQ(codec.device_of("rtfuse/hal/can1"), -1);
}

TEST(HalRecordCodec, EncodeRefusesWhatTheTableDoesNotList) {
  HalRecordCodec codec(sample_info().devices);
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
  HalRecordCodec codec(sample_info().devices);
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
  HalRecordCodec codec(sample_info().devices);
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
  HalRecordCodec codec(sample_info().devices);
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
  HalRecordCodec codec(sample_info().devices);
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

TEST(HalRecordCodec, ANegativeTickSeqIsRefused) {
  // The loop counts its ticks from 0; the loader's gap arithmetic relies on it.
  HalRecordCodec codec(sample_info().devices);
  std::uint8_t buf[kMaxHalRecordSize];
  const std::int64_t consumed[1] = {0};
  LoopTick tick;
  std::string err;
  const int n = codec.encode_tick(0, -1, consumed, 1, 0u, buf, sizeof buf);
  EXPECT_FALSE(HalRecordCodec::decode_tick(buf, n, &tick, &err));
  EXPECT_NE(err.find("negative tick seq -1"), std::string::npos) << err;
}

TEST(HalRecordingInfo, RoundTripsAndChecksTheVersion) {
  const RecordingInfo info = sample_info();
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
  RecordingInfo info = sample_info();
  EXPECT_TRUE(validate(info, &err)) << err;
  info.devices[3].name = "can0";
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("device 3 'can0': the name is also device 0's"), std::string::npos) << err;
  info = sample_info();
  info.devices[1].stream = 2;
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("stream 2 does not exist"), std::string::npos) << err;
  info = sample_info();
  info.devices[0].name = "can/0";
  EXPECT_FALSE(validate(info, &err));
  info = sample_info();
  info.streams.clear();
  EXPECT_FALSE(validate(info, &err));
}

// Writes the int32 at byte `at` of an encoded record (LCM is big-endian).
void poke_i32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

TEST(HalRecordingInfo, ImpossibleStringLengthsAreRefusedBeforeDecoding) {
  // lcm-gen's decoder copies len - 1 bytes for any length: 2^31 read 2 GiB
  // past the record (issue 11, defect 1).
  const std::vector<std::uint8_t> good = encode_recording_info(sample_info());
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
  const RecordingInfo info = sample_info();
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

TEST(HalRecordingEnd, ImpossibleCountsAreRefused) {
  RecordingEnd end;
  std::string err;
  const auto negative = encode_recording_end({2'000, 1, -4});
  EXPECT_FALSE(decode_recording_end(negative.data(), static_cast<int>(negative.size()), &end, &err));
  EXPECT_NE(err.find("impossible lost event count -4"), std::string::npos) << err;
  const auto none = encode_recording_end({2'000, 0, 0});
  EXPECT_FALSE(decode_recording_end(none.data(), static_cast<int>(none.size()), &end, &err));
  EXPECT_NE(err.find("impossible event count 0"), std::string::npos) << err;
}

TEST(HalRecordingInfo, AStartTimeBeyondNanosecondsIsRefused) {
  RecordingInfo info = sample_info();
  std::vector<std::uint8_t> bytes = encode_recording_info(info);
  for (int i = 0; i < 8; ++i) bytes[8 + static_cast<std::size_t>(i)] = i == 0 ? 0x7f : 0xff;  // utime INT64_MAX
  RecordingInfo back;
  std::string err;
  EXPECT_FALSE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err));
  EXPECT_NE(err.find("start time 9223372036854775807 us is beyond what nanoseconds can hold"), std::string::npos)
      << err;
}

}  // namespace
}  // namespace rtfuse::transport

// --- files the configuration names (recording_file_t) ------------------------

namespace rtfuse::transport {
namespace {

using test::calibration_file;
using test::sample_info;

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

  RecordingInfo info = sample_info();
  info.config_text = std::string("a = 1\0b = 2", 11);
  EXPECT_FALSE(validate(info, &err));
  EXPECT_NE(err.find("configuration text has a NUL byte at offset 5"), std::string::npos) << err;
  // What the recorder would have written from it: unreadable.
  const std::vector<std::uint8_t> bytes = encode_recording_info(info);
  RecordingInfo back;
  EXPECT_FALSE(decode_recording_info(bytes.data(), static_cast<int>(bytes.size()), &back, &err));
}

TEST(HalRecordedFile, LimitsAndDuplicatesAreRefused) {
  RecordingInfo info = sample_info();
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

}  // namespace
}  // namespace rtfuse::transport
