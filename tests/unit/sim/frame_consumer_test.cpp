// A second consumer of the camera's rectified pairs, plugged in beside the
// visual odometry through the frame-consumer socket alone: neither the
// camera device nor the odometry knows it. It works on a thread of its own,
// slower than the camera, and must neither stall capture nor change one bit
// of what the odometry measures; what it cannot take in time it drops and
// counts.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "core/frame_mailbox.hpp"
#include "hal/mock/sim_clock.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/camera/camera_device.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/frame_consumer.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "sim/sim_robot.hpp"
#include "support/sim_toml.hpp"

namespace frame_consumer_test {

using namespace rtfuse;  // NOLINT

class NullSink final : public MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, TimeNs) override { return true; }
};

// A consumer on a thread of its own that needs far longer per pair than the
// camera's period (a mapper on a slow core): it takes the newest waiting
// pair, checks it is whole, and holds it while the camera goes on.
class SlowConsumer final : public FrameConsumer {
 public:
  explicit SlowConsumer(FramePool& pool) : pool_(pool) {}
  ~SlowConsumer() override { stop(); }

  const char* name() const noexcept override { return "slow probe"; }
  int frames_held() const noexcept override { return 2; }  // one waiting, one in work
  void on_pair(FramePool& pool, const FramePool::Handle& newest) noexcept override { mailbox_.offer(pool, newest); }

  void start() {
    running_ = true;
    thread_ = std::thread([this] {
      while (running_.load()) {
        FramePool::Handle h = mailbox_.take();
        if (!h.valid()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
          continue;
        }
        const FramePool::Frame f = pool_.frame(h);
        // The pair is the one it was lent, whole, while the camera goes on.
        std::uint64_t sum = 0;
        for (int y = 0; y < f.height; ++y) sum += f.left[static_cast<std::size_t>(y) * f.stride + f.width / 2];
        if (f.frame_id <= last_id_ || f.width <= 0 || sum == 0) bad_.fetch_add(1);
        last_id_ = f.frame_id;
        // Slower than the camera whatever either's speed (a sanitizer, a
        // loaded machine): it works until three more pairs were offered.
        const std::int64_t until = mailbox_.offered() + 3;
        const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        while (running_.load() && mailbox_.offered() < until && std::chrono::steady_clock::now() < give_up) {
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        pool_.release(h);
        taken_.fetch_add(1);
      }
    });
  }
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
    mailbox_.clear(pool_);
  }

  std::int64_t taken() const { return taken_.load(); }
  std::int64_t bad() const { return bad_.load(); }
  const FrameMailbox& mailbox() const { return mailbox_; }

 private:
  FramePool& pool_;
  FrameMailbox mailbox_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::uint64_t last_id_ = 0;
  std::atomic<std::int64_t> taken_{0};
  std::atomic<std::int64_t> bad_{0};
};

// One lockstep run of the camera: the odometry's twists as bytes, the
// camera's counts, and the probe's when there was one.
struct CameraRun {
  std::vector<std::uint8_t> twists;
  std::int64_t frames = 0;
  std::int64_t pool_full = 0;
  std::int64_t vo_samples = 0;
  std::string attach_error;
  std::int64_t taken = 0, bad = 0, offered = 0, dropped = 0;
};

class FrameConsumers : public ::testing::Test {
 protected:
  // config/sim.toml with its camera and odometry; room in the pool for a
  // consumer that keeps two pairs.
  static RuntimeConfig config(int pool_frames) {
    const ConfigLoadResult r = load_config_string(test::sim_toml_text(true), test::kSimTomlPath);
    EXPECT_TRUE(r.config);
    RuntimeConfig cfg = *r.config;
    cfg.hardware.camera.pool_frames = pool_frames;
    return cfg;
  }

  // `frames` frames of the simulated drive, the camera stepped as its thread
  // would be, with the probe attached before the start when asked.
  static CameraRun run(const RuntimeConfig& cfg, int frames, bool with_probe) {
    CameraRun out;
    const TimeNs t0 = 1'000'000'000;
    hal::mock::SimClock clock(t0);
    std::string err;
    auto robot = sim::SimRobot::create(cfg, "", clock, t0, &err);
    EXPECT_TRUE(robot) << err;
    if (!robot) return out;
    NullSink sink;
    PipelineOptions options;
    options.sink = &sink;
    auto pipeline = TickPipeline::create(cfg, robot->buses(), options, &err);
    EXPECT_TRUE(pipeline) << err;
    if (!pipeline) return out;
    CameraDevice* camera = pipeline->hardware()->find<CameraDevice>("camera");
    EXPECT_NE(camera, nullptr);
    if (camera == nullptr) return out;
    std::unique_ptr<SlowConsumer> probe;
    if (with_probe) {
      probe = std::make_unique<SlowConsumer>(camera->pool());
      if (!camera->attach(*probe, &out.attach_error)) return out;
    }
    EXPECT_TRUE(pipeline->start(t0, &err)) << err;
    if (probe) probe->start();
    const int vo_sensor = source_sensor(cfg, "stereo_vo");
    EXPECT_GE(vo_sensor, 0);
    auto& ring = pipeline->core().input().ring(vo_sensor);
    est::SensorSample s;
    for (int k = 0; k < frames; ++k) {
      clock.set(robot->next_event_time("camera"));
      camera->step(kDeviceStepTimeoutNs);
      while (ring.try_pop(s)) {
        const auto* p = reinterpret_cast<const std::uint8_t*>(&s.twist);
        out.twists.insert(out.twists.end(), p, p + sizeof s.twist);
        out.twists.insert(out.twists.end(), reinterpret_cast<const std::uint8_t*>(&s.stamp),
                          reinterpret_cast<const std::uint8_t*>(&s.stamp) + sizeof s.stamp);
      }
    }
    if (probe) probe->stop();
    out.frames = camera->frames();
    out.pool_full = camera->stats().pool_full;
    out.vo_samples = camera->samples();
    if (probe) {
      out.taken = probe->taken();
      out.bad = probe->bad();
      out.offered = probe->mailbox().offered();
      out.dropped = probe->mailbox().dropped();
    }
    return out;
  }
};

TEST_F(FrameConsumers, ASlowSecondConsumerDropsPairsButNeverStallsCaptureOrChangesTheOdometry) {
  const int kFrames = 90;  // three seconds of the drive at 30 fps
  const RuntimeConfig cfg = config(6);
  const CameraRun alone = run(cfg, kFrames, false);
  ASSERT_GT(alone.vo_samples, 30) << "the odometry must be measuring for the comparison to mean anything";
  const CameraRun both = run(cfg, kFrames, true);
  ASSERT_EQ(both.attach_error, "");
  // Every frame captured and rectified, none for want of a pool slot.
  EXPECT_EQ(both.frames, alone.frames);
  EXPECT_EQ(both.frames, kFrames);
  EXPECT_EQ(both.pool_full, 0);
  // The odometry measured exactly the same twists, bit for bit.
  EXPECT_EQ(both.vo_samples, alone.vo_samples);
  EXPECT_EQ(both.twists, alone.twists);
  // The probe took pairs, whole and in order, and dropped the ones it had no
  // time for: every pair offered was taken, dropped, or still waiting.
  EXPECT_GT(both.taken, 0);
  EXPECT_EQ(both.bad, 0);
  EXPECT_EQ(both.offered, kFrames);
  EXPECT_GT(both.dropped, 0);
  EXPECT_LE(both.taken + both.dropped, both.offered);
  EXPECT_GE(both.taken + both.dropped, both.offered - 1);  // one may still wait
}

TEST_F(FrameConsumers, AConsumerThePoolCannotLendToIsRefusedWithTheFix) {
  // config/sim.toml's four pairs: capture, the newest and the preview leave
  // one, and the probe keeps two: it needs five.
  const CameraRun r = run(config(4), 1, true);
  EXPECT_EQ(r.frames, 0);
  EXPECT_NE(r.attach_error.find("'slow probe'"), std::string::npos) << r.attach_error;
  EXPECT_NE(r.attach_error.find("camera.pool_frames >= 5"), std::string::npos) << r.attach_error;
}

}  // namespace frame_consumer_test
