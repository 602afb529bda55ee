// The divergence rules (hal/replay/replay_cursor.hpp) are the same for bus
// events (ReplayStream) and camera calls (ReplayVideoLog): each test below
// runs one scenario against both, with the same expected reports up to the
// calls' own descriptions and the noun for them ("events", "calls").
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <type_traits>

#include "hal/replay/replay_stream.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::hal::replay {
namespace replay_rules_test {

// A call on a device with one argument, through each kind's own API.
struct BusCalls {
  using Log = ReplayStream;
  using Event = BusEvent;
  static constexpr const char* kNoun = "events";
  static constexpr const char* kNothing = "recorded events";

  // An I2C read of register `arg`.
  static Event call(std::uint8_t device, int arg) {
    BusEvent ev;
    ev.kind = BusEventKind::kI2cRead;
    ev.device = device;
    ev.address = 0x68;
    ev.reg = static_cast<std::uint8_t>(arg);
    ev.length = 2;
    return ev;
  }
  static Event other_kind(std::uint8_t device) {
    BusEvent ev;
    ev.kind = BusEventKind::kI2cWrite;
    ev.device = device;
    ev.address = 0x68;
    return ev;
  }
  static int argument(const Event& ev) { return ev.reg; }
  static std::string describe(int arg) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "i2c_read addr 0x68 reg 0x%02X len 2", arg);
    return buf;
  }
  static void append(Log& log, const Event& ev, std::int64_t log_event) { log.append(ev, log_event); }
  static void mark_hole(Log& log, std::int64_t log_event, std::uint32_t lost) { log.mark_hole(log_event, lost); }
  static const Event* take(Log& log, const Event& call) { return log.take(call); }
};

struct VideoCalls {
  using Log = ReplayVideoLog;
  using Event = VideoEvent;
  static constexpr const char* kNoun = "calls";
  static constexpr const char* kNothing = "recorded video calls";

  // A release of buffer `arg`.
  static Event call(std::uint8_t device, int arg) {
    VideoEvent ev;
    ev.kind = VideoCallKind::kRelease;
    ev.device = device;
    ev.index = arg;
    return ev;
  }
  static Event other_kind(std::uint8_t device) {
    VideoEvent ev;
    ev.kind = VideoCallKind::kStop;
    ev.device = device;
    return ev;
  }
  static int argument(const Event& ev) { return ev.index; }
  static std::string describe(int arg) { return "release index " + std::to_string(arg); }
  static void append(Log& log, const Event& ev, std::int64_t log_event) { log.append(ev, nullptr, log_event); }
  // A hole that lost no frame, so the report is the common one.
  static void mark_hole(Log& log, std::int64_t log_event, std::uint32_t lost) { log.mark_hole(log_event, lost, 0); }
  static const Event* take(Log& log, const Event& call) {
    const std::uint8_t* frame = nullptr;
    return log.take(call, &frame);
  }
};

template <class Kind>
class ReplayRules : public ::testing::Test {
 protected:
  using Log = typename Kind::Log;
  using Event = typename Kind::Event;

  // Calls with arguments 1, 2, 3 at log events 10, 11, 12.
  void record(Log& log, int n = 3) {
    for (int i = 0; i < n; ++i) Kind::append(log, Kind::call(0, i + 1), 10 + i);
  }
  const Event* take(Log& log, int arg, std::uint8_t device = 0) { return Kind::take(log, Kind::call(device, arg)); }
  // A call's description with the device named after the call's name.
  static std::string on(const std::string& device, int arg) {
    std::string call = Kind::describe(arg);
    return call.insert(call.find(' '), " on " + device);
  }
  static std::string end_report(const std::string& head, int arg) {
    return head + ": driver called " + on("device 0", arg);
  }
};

using Kinds = ::testing::Types<BusCalls, VideoCalls>;
struct KindNames {
  template <class Kind>
  static std::string GetName(int) {
    return std::is_same_v<Kind, BusCalls> ? "Bus" : "Video";
  }
};
TYPED_TEST_SUITE(ReplayRules, Kinds, KindNames);

TYPED_TEST(ReplayRules, TheSameCallGetsTheRecordedOne) {
  typename TypeParam::Log log("s");
  this->record(log);
  const auto* rec = this->take(log, 1);
  ASSERT_NE(rec, nullptr);
  EXPECT_EQ(TypeParam::argument(*rec), 1);
  EXPECT_EQ(log.position(), 1u);
  EXPECT_EQ(log.remaining(), 2u);
  EXPECT_EQ(log.size(), 3u);
  EXPECT_EQ(log.log_event(1), 11);
  EXPECT_FALSE(log.diverged());
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kNone);
  EXPECT_STREQ(log.divergence(), "");
  EXPECT_EQ(log.divergence_event(), -1);
  EXPECT_FALSE(log.at_end());
}

TYPED_TEST(ReplayRules, AnotherArgumentDivergesAndTheFirstDivergenceWins) {
  typename TypeParam::Log log("s");
  this->record(log);
  ASSERT_NE(this->take(log, 1), nullptr);
  EXPECT_EQ(this->take(log, 7), nullptr);
  const std::string report = "event 11: recorded " + TypeParam::describe(2) + ", driver called " + TypeParam::describe(7);
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kMismatch);
  EXPECT_EQ(log.divergence(), report);
  EXPECT_EQ(log.divergence_event(), 11);
  EXPECT_EQ(log.position(), 1u);
  EXPECT_FALSE(log.at_end());
  // Every later take fails, the recorded call included, and the report stays.
  EXPECT_EQ(this->take(log, 2), nullptr);
  EXPECT_EQ(this->take(log, 9), nullptr);
  EXPECT_EQ(TypeParam::take(log, TypeParam::other_kind(0)), nullptr);
  EXPECT_EQ(log.divergence(), report);
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kMismatch);
  EXPECT_EQ(log.position(), 1u);
}

TYPED_TEST(ReplayRules, AnotherKindOrDeviceDiverges) {
  {
    typename TypeParam::Log log("s");
    this->record(log);
    EXPECT_EQ(TypeParam::take(log, TypeParam::other_kind(0)), nullptr);
    EXPECT_EQ(log.divergence_kind(), DivergenceKind::kMismatch);
    EXPECT_EQ(log.divergence_event(), 10);
  }
  {
    typename TypeParam::Log log("s");
    log.set_device_name(0, "dev0");
    this->record(log);
    EXPECT_EQ(this->take(log, 1, /*device=*/1), nullptr);
    EXPECT_EQ(log.divergence_kind(), DivergenceKind::kMismatch);
    // Only a call on another device names the devices: unnamed ones by number.
    EXPECT_EQ(log.divergence(),
              "event 10: recorded " + this->on("dev0", 1) + ", driver called " + this->on("device 1", 1));
  }
}

TYPED_TEST(ReplayRules, ACallAfterTheLastIsACleanEndOfStream) {
  typename TypeParam::Log log("s");
  this->record(log, 2);
  ASSERT_NE(this->take(log, 1), nullptr);
  ASSERT_NE(this->take(log, 2), nullptr);
  EXPECT_TRUE(log.at_end());
  EXPECT_FALSE(log.diverged());
  EXPECT_EQ(this->take(log, 3), nullptr);
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kEndOfStream);
  EXPECT_EQ(log.divergence_event(), 11);  // the last one replayed
  EXPECT_TRUE(log.at_end()) << "running past the end is still a clean stop";
  EXPECT_EQ(log.divergence(),
            this->end_report(std::string("stream 's' ended after event 11 (2 ") + TypeParam::kNoun + " replayed)", 3));
  EXPECT_EQ(this->take(log, 3), nullptr);
  EXPECT_EQ(log.position(), 2u);
}

TYPED_TEST(ReplayRules, AnEmptyStreamSaysSo) {
  typename TypeParam::Log log("s");
  EXPECT_TRUE(log.at_end());
  EXPECT_EQ(this->take(log, 1), nullptr);
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kEndOfStream);
  EXPECT_EQ(log.divergence_event(), -1);
  EXPECT_EQ(log.divergence(), this->end_report(std::string("stream 's' has no ") + TypeParam::kNothing, 1));
}

TYPED_TEST(ReplayRules, AHoleEndsTheStreamThereAndTheReportSaysWhy) {
  typename TypeParam::Log log("s");
  this->record(log, 1);
  TypeParam::mark_hole(log, 15, 3);
  // Nothing after the first hole is replayable: later calls and holes are dropped.
  TypeParam::append(log, TypeParam::call(0, 2), 15);
  TypeParam::mark_hole(log, 20, 9);
  EXPECT_TRUE(log.has_hole());
  EXPECT_EQ(log.hole_event(), 15);
  EXPECT_EQ(log.size(), 1u);
  ASSERT_NE(this->take(log, 1), nullptr);
  EXPECT_TRUE(log.at_end());
  EXPECT_EQ(this->take(log, 2), nullptr);
  EXPECT_EQ(log.divergence_kind(), DivergenceKind::kEndOfStream);
  EXPECT_EQ(log.divergence_event(), 10);
  EXPECT_TRUE(log.at_end());
  const std::string lost = std::string(", where the recorder lost 3 ") + TypeParam::kNoun + " (";
  const std::string replayed = std::string("its ring was full while recording; 1 ") + TypeParam::kNoun + " replayed)";
  const std::string report = log.divergence();
  EXPECT_EQ(report.rfind("stream 's' ends at event 15" + lost, 0), 0u) << report;
  EXPECT_NE(report.find(replayed + ": driver called "), std::string::npos) << report;
}

TYPED_TEST(ReplayRules, TheReportIsReadFromAnotherThread) {
  typename TypeParam::Log log("s");
  this->record(log);
  std::string seen;
  std::atomic<bool> reading{false};
  std::thread reader([&] {
    reading.store(true);
    while (!log.diverged()) std::this_thread::yield();
    seen = log.divergence();
  });
  while (!reading.load()) std::this_thread::yield();
  ASSERT_NE(this->take(log, 1), nullptr);
  EXPECT_EQ(this->take(log, 5), nullptr);
  reader.join();
  EXPECT_EQ(seen, "event 11: recorded " + TypeParam::describe(2) + ", driver called " + TypeParam::describe(5));
}

TYPED_TEST(ReplayRules, TakingAndDivergingNeverAllocate) {
  typename TypeParam::Log log("s");
  log.set_device_name(0, "a-rather-long-device-name-past-any-small-string-buffer");
  this->record(log);
  rtfuse::test::AllocScope scope;
  ASSERT_NE(this->take(log, 1), nullptr);
  EXPECT_EQ(this->take(log, 1, /*device=*/1), nullptr);  // names both devices
  EXPECT_EQ(this->take(log, 2), nullptr);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace replay_rules_test
}  // namespace rtfuse::hal::replay
