#pragma once
// The live runtime: the fixed-rate loop thread (rtfuse-loop), the publisher
// thread (rtfuse-pub), the LCM input thread (rtfuse-lcmin) and, with an IMU
// driver, the IMU thread (rtfuse-imu) around one FusionCore. Everything is allocated in create(); the threads allocate
// nothing once running.
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "runtime/fusion_core.hpp"
#include "runtime/hal_buses.hpp"
#include "runtime/hardware.hpp"
#include "runtime/publisher.hpp"
#include "transport/lcm_node.hpp"

namespace rtfuse {

class Runtime {
 public:
  // buses: where the configured drivers find their devices (none needed
  // without [can] / [mpu]).
  static std::unique_ptr<Runtime> create(const RuntimeConfig& cfg, std::string* error);
  static std::unique_ptr<Runtime> create(const RuntimeConfig& cfg, const HalBuses& buses, std::string* error);
  ~Runtime();

  // Applies the real-time settings and starts the threads. Returns false (and
  // *error) when a required setting is refused or a thread cannot start;
  // refused optional settings are written to *warnings.
  bool start(std::string* error, std::string* warnings);
  void stop();

  Snapshot latest() const;
  transport::LcmNode& lcm() { return *lcm_; }
  const RuntimeConfig& config() const { return core_->config(); }
  // Set by the loop after its first steady tick; tests and tools use it to
  // know when start-up allocations are over.
  bool steady() const { return steady_.load(std::memory_order_acquire); }

 private:
  Runtime() = default;
  void loop_thread();
  void publisher_thread();
  void input_thread();
  void imu_thread();
  static void on_lcm(const char* channel, const std::uint8_t* data, int size, std::int64_t, void* user);

  std::unique_ptr<FusionCore> core_;
  std::unique_ptr<Publisher> publisher_;
  std::unique_ptr<transport::LcmNode> lcm_;
  std::unique_ptr<Hardware> hardware_;
  std::atomic<bool> running_{false};
  std::atomic<bool> steady_{false};
  std::atomic<bool> rt_failed_{false};
  std::string rt_warnings_;
  std::thread loop_, pub_, lcmin_, imu_;
};

}  // namespace rtfuse
