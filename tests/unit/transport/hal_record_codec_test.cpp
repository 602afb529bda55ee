// The records of bus calls (hal_can_t, hal_i2c_t, hal_gpio_t, hal_clock_t,
// hal_serial_t) and loop ticks: round trips byte for byte, refusals that
// name what is wrong, no allocation once warm.
#include "transport/hal_record_codec.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "rtfuse/hal_can_t.hpp"
#include "rtfuse/hal_serial_t.hpp"
#include "support/alloc_counter.hpp"
#include "support/hal_record_samples.hpp"

namespace rtfuse::transport {
namespace hal_record_codec_test {

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

}  // namespace hal_record_codec_test
}  // namespace rtfuse::transport
