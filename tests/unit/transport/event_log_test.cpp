#include "transport/event_log.hpp"

#include <gtest/gtest.h>

#include "support/temp_file.hpp"
#include <lcm/eventlog.h>
#include <malloc.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace rtfuse::transport {
namespace event_log_test {

// A per-test file in the temp dir, removed afterwards.
// A log path of this test, removed afterwards.
class TempLog : public test::TempFile {
 public:
  explicit TempLog(const std::string& name) : TempFile(name, ".lcmlog") {}
};

std::vector<std::uint8_t> payload(int event, std::size_t size) {
  std::vector<std::uint8_t> bytes(size);
  for (std::size_t i = 0; i < size; ++i) bytes[i] = static_cast<std::uint8_t>(event * 31 + i * 7);
  return bytes;
}

std::vector<char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Two events: 28 + 3 + 4 = 35 bytes, then 28 + 3 + 300 = 331 bytes.
void write_two_events(const std::string& path) {
  EventLogWriter w;
  std::string err;
  ASSERT_TRUE(w.open(path, &err)) << err;
  const auto a = payload(0, 4);
  const auto b = payload(1, 300);
  ASSERT_TRUE(w.write(10, "IMU", a.data(), a.size(), &err)) << err;
  ASSERT_TRUE(w.write(20, "ODO", b.data(), b.size(), &err)) << err;
  ASSERT_TRUE(w.close(&err)) << err;
}

TEST(EventLog, RoundTripsManyEvents) {
  TempLog log("roundtrip");
  constexpr int kEvents = 2000;
  std::string err;
  {
    EventLogWriter w;
    ASSERT_TRUE(w.open(log.path(), &err)) << err;
    for (int i = 0; i < kEvents; ++i) {
      // Sizes from 0 to well above the writer's buffer, to cross every path.
      const std::size_t size = (i % 97 == 0) ? 200'000 : static_cast<std::size_t>(i % 500);
      const auto bytes = payload(i, size);
      const std::string channel = "CH_" + std::to_string(i % 7);
      ASSERT_TRUE(w.write(1'000'000 + i * 10, channel, bytes.data(), bytes.size(), &err)) << err;
    }
    EXPECT_EQ(w.events_written(), kEvents);
    ASSERT_TRUE(w.close(&err)) << err;
  }
  EventLogReader r;
  ASSERT_TRUE(r.open(log.path(), &err)) << err;
  LogEvent ev;
  for (int i = 0; i < kEvents; ++i) {
    ASSERT_EQ(r.next(&ev, &err), ReadStatus::kEvent) << err;
    const std::size_t size = (i % 97 == 0) ? 200'000 : static_cast<std::size_t>(i % 500);
    EXPECT_EQ(ev.event_number, i);
    EXPECT_EQ(ev.timestamp_us, 1'000'000 + i * 10);
    EXPECT_EQ(ev.channel, "CH_" + std::to_string(i % 7));
    ASSERT_EQ(ev.size, size);
    const auto expected = payload(i, size);
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), ev.data)) << "event " << i;
  }
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kEnd);
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kEnd);
  EXPECT_EQ(r.events_read(), kEvents);
}

TEST(EventLog, EmptyFileIsACleanEnd) {
  TempLog log("empty");
  write_file(log.path(), {});
  EventLogReader r;
  std::string err;
  ASSERT_TRUE(r.open(log.path(), &err)) << err;
  LogEvent ev;
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kEnd);
}

TEST(EventLog, ReadsALogWrittenByLcm) {
  TempLog log("lcm_written");
  lcm_eventlog_t* l = lcm_eventlog_create(log.path().c_str(), "w");
  ASSERT_NE(l, nullptr);
  std::vector<std::vector<std::uint8_t>> datas;
  for (int i = 0; i < 50; ++i) {
    datas.push_back(payload(i, static_cast<std::size_t>(i * 13)));
    std::string channel = "LCM_CHANNEL_" + std::to_string(i);
    lcm_eventlog_event_t e{};
    e.timestamp = 1'700'000'000'000'000 + i;
    e.channellen = static_cast<std::int32_t>(channel.size());
    e.datalen = static_cast<std::int32_t>(datas.back().size());
    e.channel = channel.data();
    e.data = datas.back().data();
    ASSERT_EQ(lcm_eventlog_write_event(l, &e), 0);
  }
  lcm_eventlog_destroy(l);

  EventLogReader r;
  std::string err;
  ASSERT_TRUE(r.open(log.path(), &err)) << err;
  LogEvent ev;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(r.next(&ev, &err), ReadStatus::kEvent) << err;
    EXPECT_EQ(ev.event_number, i);
    EXPECT_EQ(ev.timestamp_us, 1'700'000'000'000'000 + i);
    EXPECT_EQ(ev.channel, "LCM_CHANNEL_" + std::to_string(i));
    ASSERT_EQ(ev.size, datas[static_cast<std::size_t>(i)].size());
    EXPECT_TRUE(std::equal(datas[static_cast<std::size_t>(i)].begin(),
                           datas[static_cast<std::size_t>(i)].end(), ev.data));
  }
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kEnd) << err;
}

TEST(EventLog, LcmReadsALogWeWrote) {
  TempLog log("we_wrote");
  write_two_events(log.path());
  lcm_eventlog_t* l = lcm_eventlog_create(log.path().c_str(), "r");
  ASSERT_NE(l, nullptr);
  lcm_eventlog_event_t* e = lcm_eventlog_read_next_event(l);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->eventnum, 0);
  EXPECT_EQ(e->timestamp, 10);
  EXPECT_EQ(std::string(e->channel, static_cast<std::size_t>(e->channellen)), "IMU");
  EXPECT_EQ(e->datalen, 4);
  lcm_eventlog_free_event(e);
  e = lcm_eventlog_read_next_event(l);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->eventnum, 1);
  EXPECT_EQ(e->timestamp, 20);
  EXPECT_EQ(std::string(e->channel, static_cast<std::size_t>(e->channellen)), "ODO");
  ASSERT_EQ(e->datalen, 300);
  const auto b = payload(1, 300);
  EXPECT_TRUE(std::equal(b.begin(), b.end(), static_cast<const std::uint8_t*>(e->data)));
  lcm_eventlog_free_event(e);
  EXPECT_EQ(lcm_eventlog_read_next_event(l), nullptr);
  lcm_eventlog_destroy(l);
}

// Reads until something other than kEvent; returns it, with the error text.
ReadStatus drain(const std::string& path, std::string* err, int* events) {
  EventLogReader r;
  if (!r.open(path, err)) return ReadStatus::kError;
  LogEvent ev;
  *events = 0;
  ReadStatus s;
  while ((s = r.next(&ev, err)) == ReadStatus::kEvent) ++*events;
  return s;
}

TEST(EventLog, TruncatedMidDataIsAnErrorNotAnEnd) {
  TempLog log("trunc_data");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  ASSERT_EQ(bytes.size(), 35u + 331u);
  bytes.resize(35 + 28 + 3 + 120);
  write_file(log.path(), bytes);
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(events, 1);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 is truncated: header says 300 data bytes, 120 remain "
                     "(the log ends mid-event)");
}

TEST(EventLog, ALengthPastTheEndOfTheFileReservesNothing) {
  // The fuzzer's slowest inputs: a data length of 200 MiB in a 200-byte file
  // made the reader allocate 200 MiB before it found the bytes missing.
  TempLog log("huge_length");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  const std::uint32_t claimed = 200u << 20;
  for (int i = 0; i < 4; ++i) bytes[35 + 24 + static_cast<std::size_t>(i)] = static_cast<char>(claimed >> (24 - 8 * i));
  write_file(log.path(), bytes);
  EventLogReader r;
  std::string err;
  ASSERT_TRUE(r.open(log.path(), &err)) << err;
  LogEvent ev;
  ASSERT_EQ(r.next(&ev, &err), ReadStatus::kEvent);
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kError);
  EXPECT_EQ(err, "file " + log.path() + ": event 1 at byte 35 is truncated: header says " + std::to_string(claimed) +
                     " data bytes, 300 remain (the log ends mid-event)");
  // glibc serves a block that large with mmap: none is held while the reader
  // lives (ASan's allocator reports nothing here, the plain build checks).
  EXPECT_LT(mallinfo2().hblkhd, static_cast<std::size_t>(64) << 20);
}

TEST(EventLog, TruncatedMidHeaderIsAnError) {
  TempLog log("trunc_header");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  bytes.resize(35 + 10);
  write_file(log.path(), bytes);
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(events, 1);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 is truncated: 10 of 28 header bytes remain (the log "
                     "ends mid-event)");
}

TEST(EventLog, TruncatedMidChannelIsAnError) {
  TempLog log("trunc_channel");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  bytes.resize(35 + 28 + 1);
  write_file(log.path(), bytes);
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 is truncated: header says 3 channel bytes, 1 remain "
                     "(the log ends mid-event)");
}

TEST(EventLog, ErrorIsSticky) {
  TempLog log("sticky");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  bytes.resize(40);
  write_file(log.path(), bytes);
  EventLogReader r;
  std::string err;
  ASSERT_TRUE(r.open(log.path(), &err));
  LogEvent ev;
  ASSERT_EQ(r.next(&ev, &err), ReadStatus::kEvent);
  ASSERT_EQ(r.next(&ev, &err), ReadStatus::kError);
  const std::string first = err;
  err.clear();
  EXPECT_EQ(r.next(&ev, &err), ReadStatus::kError);
  EXPECT_EQ(err, first);
}

TEST(EventLog, BadSyncWordNamesTheOffset) {
  TempLog log("bad_sync");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  bytes[35] = 0x12;
  bytes[36] = 0x34;
  bytes[37] = 0x56;
  bytes[38] = 0x78;
  write_file(log.path(), bytes);
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(events, 1);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 has a bad sync word 0x12345678 (expected 0xEDA1DA01): "
                     "not an LCM log, or corrupt from here on");
}

TEST(EventLog, GarbageFileIsRejectedAtByteZero) {
  TempLog log("garbage");
  write_file(log.path(), std::vector<char>(100, 'x'));
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(events, 0);
  EXPECT_NE(err.find("event 0 at byte 0 has a bad sync word 0x78787878"), std::string::npos) << err;
}

void set_be32(std::vector<char>* bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    (*bytes)[at + static_cast<std::size_t>(i)] = static_cast<char>(v >> (24 - 8 * i));
}

TEST(EventLog, AbsurdLengthsAreRejectedBeforeReading) {
  TempLog log("lengths");
  write_two_events(log.path());
  const auto original = read_file(log.path());
  std::string err;
  int events = 0;

  auto bytes = original;
  set_be32(&bytes, 35 + 24, 0xFFFFFFFFu);  // data length -1
  write_file(log.path(), bytes);
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 has an invalid data length -1 (expected 0..268435456): "
                     "the log is corrupt");

  bytes = original;
  set_be32(&bytes, 35 + 24, 300u * 1024 * 1024);
  write_file(log.path(), bytes);
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_NE(err.find("invalid data length 314572800"), std::string::npos) << err;

  bytes = original;
  set_be32(&bytes, 35 + 20, 5000);
  write_file(log.path(), bytes);
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(err, "file " + log.path() +
                     ": event 1 at byte 35 has an invalid channel length 5000 (expected 1..4096): "
                     "the log is corrupt");

  bytes = original;
  set_be32(&bytes, 20, 0x80000000u);
  write_file(log.path(), bytes);
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_NE(err.find("event 0 at byte 0 has an invalid channel length -2147483648"),
            std::string::npos)
      << err;
}

TEST(EventLog, UnreadableFileNamesTheCause) {
  EventLogReader r;
  std::string err;
  const std::string path = testing::TempDir() + "rtfuse_no_such_dir/none.lcmlog";
  EXPECT_FALSE(r.open(path, &err));
  EXPECT_EQ(err, "cannot open log file " + path + ": No such file or directory");
}

TEST(EventLog, ADirectoryIsRefusedAtOpen) {
  EventLogReader r;
  std::string err;
  const std::string dir = testing::TempDir();
  EXPECT_FALSE(r.open(dir, &err));
  EXPECT_EQ(err, "cannot open log file " + dir + ": it is a directory (give the .lcm file in it)");
}

TEST(EventLog, AStampBeyondNanosecondsIsCorrupt) {
  // Every consumer turns utime into int64 nanoseconds: 9.3e15 us would
  // overflow (issue 11, defect 3).
  TempLog log("stamp");
  write_two_events(log.path());
  auto bytes = read_file(log.path());
  set_be32(&bytes, 35 + 12, 0x00210000u);  // event 1's stamp: 0x0021000000000014 us = 9.29e15
  write_file(log.path(), bytes);
  std::string err;
  int events = 0;
  EXPECT_EQ(drain(log.path(), &err, &events), ReadStatus::kError);
  EXPECT_EQ(events, 1);
  EXPECT_EQ(err, "file " + log.path() + ": event 1 at byte 35 has the timestamp 9288674231451668 us, beyond what "
                                        "nanoseconds can hold (+-9223372036854775 us): the log is corrupt");
}

TEST(EventLog, WriterRejectsWhatTheReaderWouldRefuse) {
  TempLog log("writer_reject");
  EventLogWriter w;
  std::string err;
  ASSERT_TRUE(w.open(log.path(), &err)) << err;
  const std::uint8_t byte = 1;
  EXPECT_FALSE(w.write(0, "", &byte, 1, &err));
  EXPECT_NE(err.find("has length 0"), std::string::npos) << err;
  EXPECT_FALSE(w.write(0, std::string(5000, 'c'), &byte, 1, &err));
  EXPECT_TRUE(w.write(0, "OK", nullptr, 0, &err)) << err;
  EXPECT_EQ(w.events_written(), 1);
  EXPECT_TRUE(w.close(&err)) << err;
  EXPECT_FALSE(w.write(0, "OK", &byte, 1, &err));

  EventLogWriter bad;
  EXPECT_FALSE(bad.open(testing::TempDir() + "rtfuse_no_such_dir/x.lcmlog", &err));
  EXPECT_NE(err.find("No such file or directory"), std::string::npos) << err;
}

}  // namespace event_log_test
}  // namespace rtfuse::transport
