// The records a HAL recording keeps about itself: recording_info_t (the
// format version, the device table and its validation), recording_file_t
// (a file the configuration names) and recording_end_t.
#include "transport/recording_info.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "support/hal_record_samples.hpp"

namespace rtfuse::transport {
namespace recording_info_test {

using test::calibration_file;
using test::sample_info;

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

// --- files the configuration names (recording_file_t) ------------------------

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

}  // namespace recording_info_test
}  // namespace rtfuse::transport
