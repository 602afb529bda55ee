// A HAL recording of a simulated drive replays to the same estimate, byte
// for byte; a recording that no longer matches what the drivers do is
// reported (a different sent frame: divergence at its log event; a
// different byte read: outputs that differ, named), and a replay with
// another configuration is refused with both hashes.
#include "runtime/replay/hal_replay.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <utility>
#include <string>

#include <gtest/gtest.h>

#include "runtime/config/config_loader.hpp"
#include "runtime/pipeline/recording_tap.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "sim/sim_drive.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"
#include "support/sim_toml.hpp"

namespace rtfuse {
namespace hal_replay_test {

using hal::BusEvent;
using hal::BusEventKind;
using hal::replay::ReplayStream;

const std::string kSimToml = RTFUSE_SOURCE_DIR "/config/sim.toml";
const std::string kStraight = RTFUSE_SOURCE_DIR "/config/scenarios/straight.toml";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string hex64(std::int64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// One 9 s straight drive of config/sim.toml, recorded once for every test
// here, and the recording loaded fresh for each (tests alter their copy).
class HalReplay : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string base = testing::TempDir() + "rtfuse_hal_replay_" + std::to_string(::getpid());
    scenario_path_ = new std::string(base + "_short.toml");
    record_path_ = new std::string(base + ".lcm");
    // straight.toml shortened to 2 m: 2 s stop, 4 s of driving, 2 s stop, 1 s more.
    std::string scenario = read_text(kStraight);
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"duration_s = 20.0", "duration_s = 9.0"},
                                   {"length_m = 10.0", "length_m = 2.0"}}) {
      const std::size_t at = scenario.find(from);
      ASSERT_NE(at, std::string::npos) << from;
      scenario.replace(at, from.size(), to);
    }
    std::ofstream(*scenario_path_) << scenario;

    config_text_ = new std::string(test::sim_toml_text(false));
    const ConfigLoadResult c = load_config_string(*config_text_, kSimToml);
    for (const auto& e : c.errors) ADD_FAILURE() << e.to_string();
    ASSERT_TRUE(c.ok());
    config_ = new RuntimeConfig(*c.config);
    sim::DriveOptions opt;
    opt.scenario_path = *scenario_path_;
    opt.record_path = *record_path_;
    opt.config_text = *config_text_;
    drive_ = new sim::DriveResult(sim::run_sim_drive(*config_, opt, nullptr));
  }
  static void TearDownTestSuite() {
    std::remove(scenario_path_->c_str());
    std::remove(record_path_->c_str());
    delete scenario_path_;
    delete record_path_;
    delete config_text_;
    delete config_;
    delete drive_;
  }

  void SetUp() override {
    ASSERT_NE(drive_, nullptr) << "the recorded drive was not set up";
    ASSERT_TRUE(drive_->ok) << drive_->error;
    ASSERT_EQ(drive_->recording_lost, 0);
    transport::EventLogReader reader;
    std::string err;
    ASSERT_TRUE(reader.open(*record_path_, &err)) << err;
    ASSERT_TRUE(load_hal_recording(reader, {}, &rec_, &err)) << err;
    ASSERT_TRUE(rec_.warnings.empty()) << rec_.warnings.front();
  }

  int stream(const char* name) const {
    for (std::size_t i = 0; i < rec_.info.streams.size(); ++i) {
      if (rec_.info.streams[i] == name) return static_cast<int>(i);
    }
    ADD_FAILURE() << "no stream " << name;
    return 0;
  }

  // Replaces stream `s` by a copy whose event `index` went through `edit`,
  // the way a corrupted or hand-edited recording would load.
  template <class Edit>
  void alter(int s, std::size_t index, Edit&& edit) {
    const ReplayStream& old = *rec_.streams[static_cast<std::size_t>(s)];
    auto copy = std::make_unique<ReplayStream>(old.name());
    copy->reserve(old.size());
    for (std::size_t i = 0; i < old.size(); ++i) {
      BusEvent ev = old.event(i);
      if (i == index) edit(ev);
      copy->append(ev, old.log_event(i));
    }
    for (std::size_t d = 0; d < rec_.info.devices.size(); ++d) {
      copy->set_device_name(static_cast<std::uint8_t>(d), rec_.info.devices[d].name);
    }
    rec_.streams[static_cast<std::size_t>(s)] = std::move(copy);
  }

  // Index of the n-th (0-based) event of `kind` in stream s that `pick` accepts.
  template <class Pick>
  std::size_t find(int s, BusEventKind kind, int n, Pick&& pick) const {
    const ReplayStream& st = *rec_.streams[static_cast<std::size_t>(s)];
    for (std::size_t i = 0; i < st.size(); ++i) {
      const BusEvent ev = st.event(i);
      if (ev.kind == kind && pick(ev) && n-- == 0) return i;
    }
    ADD_FAILURE() << "no such event";
    return 0;
  }

  static std::string* scenario_path_;
  static std::string* record_path_;
  static std::string* config_text_;
  static RuntimeConfig* config_;
  static sim::DriveResult* drive_;
  HalRecording rec_;
};

std::string* HalReplay::scenario_path_ = nullptr;
std::string* HalReplay::record_path_ = nullptr;
std::string* HalReplay::config_text_ = nullptr;
RuntimeConfig* HalReplay::config_ = nullptr;
sim::DriveResult* HalReplay::drive_ = nullptr;

TEST_F(HalReplay, ReproducesTheDriveBitForBit) {
  EXPECT_EQ(drive_->ticks, 9 * 200 + 1);
  EXPECT_EQ(static_cast<std::int64_t>(rec_.ticks.size()), drive_->ticks);
  EXPECT_EQ(rec_.lost_events, 0);
  EXPECT_EQ(rec_.missing_ticks, 0);
  EXPECT_EQ(rec_.info.config_hash, transport::config_text_hash(*config_text_));

  const HalReplayResult r = replay_hal_recording(rec_, *config_, nullptr, nullptr);
  ASSERT_TRUE(r.ok) << r.error << r.note;
  EXPECT_FALSE(r.diverged);
  EXPECT_FALSE(r.ended_early) << r.note;
  EXPECT_EQ(r.ticks, drive_->ticks);
  // 9 s at 50 Hz odometry, pose, tf, raw wheels and 10 Hz state.
  EXPECT_GT(r.compared, 900);
  EXPECT_EQ(r.identical, r.compared) << r.first_mismatch;
  EXPECT_EQ(r.recorded_not_reproduced, 0);
  EXPECT_EQ(r.first_mismatch, "");
  EXPECT_GT(r.published, r.compared) << "diagnostics are published, not compared";
  // Every recorded bus call was asked for again.
  for (const auto& s : rec_.streams) EXPECT_EQ(s->remaining(), 0u) << s->name();
  EXPECT_TRUE(r.final.initialized);
  EXPECT_EQ(std::memcmp(r.final.state, drive_->final.state, sizeof r.final.state), 0);
  EXPECT_EQ(std::memcmp(r.final.covariance, drive_->final.covariance, sizeof r.final.covariance), 0);
  EXPECT_EQ(r.final.seq, drive_->final.seq);
}

TEST_F(HalReplay, ChangedFirstSentFrameDivergesAtItsLogEvent) {
  const int loop = stream(kLoopStream);
  const std::size_t i = find(loop, BusEventKind::kCanSend, 0, [](const BusEvent&) { return true; });
  const ReplayStream& st = *rec_.streams[static_cast<std::size_t>(loop)];
  // The first frame the loop sent is the NMT start of node 1.
  const BusEvent first = st.event(i);
  ASSERT_EQ(first.frames[0].id, 0x000u);
  ASSERT_EQ(first.frames[0].dlc, 2);
  EXPECT_EQ(first.frames[0].data[0], 0x01);
  EXPECT_EQ(first.frames[0].data[1], 1);
  const std::int64_t event = st.log_event(i);
  alter(loop, i, [](BusEvent& ev) { ev.frames[0].data[1] = 9; });

  const HalReplayResult r = replay_hal_recording(rec_, *config_, nullptr, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.diverged);
  EXPECT_EQ(r.ticks, 0);
  EXPECT_NE(r.error.find("stream 'loop'"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("event " + std::to_string(event) + ":"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("recorded can_send id 0x000 dlc 2 [01 09]"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("driver sent id 0x000 dlc 2 [01 01]"), std::string::npos) << r.error;
}

TEST_F(HalReplay, ChangedSyncMidDriveStopsThereNotLater) {
  const int loop = stream(kLoopStream);
  // The 500th SYNC: sent by tick 500 (one per tick).
  const std::size_t i =
      find(loop, BusEventKind::kCanSend, 499, [](const BusEvent& ev) { return ev.frames[0].id == 0x080; });
  const std::int64_t event = rec_.streams[static_cast<std::size_t>(loop)]->log_event(i);
  alter(loop, i, [](BusEvent& ev) { ev.frames[0].id = 0x081; });
  const HalReplayResult r = replay_hal_recording(rec_, *config_, nullptr, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.diverged);
  // The 499 ticks before ran as recorded; the one that sent it stopped the
  // replay before publishing anything.
  EXPECT_EQ(r.ticks, 499);
  EXPECT_NE(r.error.find("event " + std::to_string(event) + ": recorded can_send id 0x081 dlc 0, driver sent id "
                                                            "0x080 dlc 0"),
            std::string::npos)
      << r.error;
  // Up to the divergence every output was the recorded one.
  EXPECT_GT(r.compared, 0);
  EXPECT_EQ(r.identical, r.compared) << r.first_mismatch;
}

TEST_F(HalReplay, ChangedImuByteChangesTheOutputsWithoutDivergence) {
  const int imu = stream("imu");
  // A data burst (ACCEL_XOUT_H, 14 bytes) mid-drive; flip gyro z by 256 LSB
  // (7.8 deg/s at 500 deg/s full scale): the same calls, another value.
  const std::size_t i = find(imu, BusEventKind::kI2cRead, 500, [](const BusEvent& ev) {
    return ev.reg == 0x3B && ev.length == 14 && ev.status == hal::HalStatus::kOk;
  });
  alter(imu, i, [](BusEvent& ev) { ev.data[12] ^= 0x01; });
  const HalReplayResult r = replay_hal_recording(rec_, *config_, nullptr, nullptr);
  ASSERT_TRUE(r.ok) << r.error << r.note;
  EXPECT_FALSE(r.diverged);
  EXPECT_EQ(r.ticks, drive_->ticks);
  EXPECT_GT(r.compared, 900);
  EXPECT_LT(r.identical, r.compared);
  EXPECT_GT(r.identical, 0) << "the outputs before the changed sample are the recorded ones";
  EXPECT_EQ(r.recorded_not_reproduced, 0);
  EXPECT_NE(r.first_mismatch, "");
  EXPECT_NE(r.first_mismatch.find("bytes recorded, the replay's"), std::string::npos) << r.first_mismatch;
  EXPECT_NE(std::memcmp(r.final.state, drive_->final.state, sizeof r.final.state), 0);
}

TEST_F(HalReplay, OtherConfigurationIsRefusedWithBothHashes) {
  const std::string other = *config_text_ + "\n# edited\n";
  const std::string msg = check_recording_config(rec_.info, other, "edited.toml");
  EXPECT_NE(msg.find(hex64(rec_.info.config_hash)), std::string::npos) << msg;
  EXPECT_NE(msg.find(hex64(transport::config_text_hash(other))), std::string::npos) << msg;
  EXPECT_NE(msg.find("'" + kSimToml + "'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'edited.toml'"), std::string::npos) << msg;
  EXPECT_NE(hex64(rec_.info.config_hash), hex64(transport::config_text_hash(other)));
  EXPECT_EQ(check_recording_config(rec_.info, *config_text_, kSimToml), "");
}

}  // namespace hal_replay_test
}  // namespace rtfuse
