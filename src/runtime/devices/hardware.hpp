#pragma once
// The devices a configuration drives, on whatever buses it is given (kernel,
// simulated robot, recording): every enabled registered device, made in
// registry order from its descriptor, frame consumers attached to their
// hosts. The loop polls the polled ones inside its tick; the live runtime
// gives each thread device a thread, and the HAL replay and the simulated
// drive step them in lockstep. No device is named here.
//
// Everything is allocated in create(); before_drain(), fill_snapshot() and
// the devices' steps (outside a re-initialisation) allocate nothing.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/devices/device.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/hal_buses.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

class Hardware final : public TickDevices {
 public:
  // The configuration is the core's. Null with *error naming the device when
  // a bus it needs is missing or its driver refuses the configuration.
  static std::unique_ptr<Hardware> create(const HalBuses& buses, FusionCore& core, std::string* error);

  // Before the threads, in registry order: NMT start to the encoder nodes,
  // the IMU's identity check. False with *error naming the device and the fix.
  bool start(TimeNs now, std::string* error);

  // Loop thread (TickDevices).
  void before_drain(TimeNs now) noexcept override;
  void fill_snapshot(Snapshot& s) noexcept override;
  int slot_count() const noexcept override { return slot_count_; }

  // Publisher thread: every device's own outputs (a camera's preview).
  void publish_due(TimeNs now, transport::MessageSink& sink) noexcept;

  // The devices that want a thread (live) or lockstep steps (replay,
  // simulation), and the name of each: its thread, its recording stream, its
  // simulated counterpart.
  int thread_device_count() const noexcept { return num_threaded_; }
  Device& thread_device(int i) noexcept { return *devices_[threaded_[i]]; }
  const char* thread_device_name(int i) const noexcept { return device_type(threaded_[i]).name(); }

  // Workers (DeviceScheduling::kWorker): live, each on a thread of its own
  // at the default priority; a replay or a lockstep drive calls
  // step_workers() after every tick and, like the live runtime once its
  // threads are joined, finish_workers() at the end.
  int worker_count() const noexcept { return num_workers_; }
  Device& worker(int i) noexcept { return *devices_[workers_[i]]; }
  const char* worker_name(int i) const noexcept { return device_type(workers_[i]).name(); }
  void step_workers() noexcept;
  void finish_workers() noexcept;
  // The LCM channels devices take input from (DeviceDescriptor::
  // input_channels), in registry order: the live runtime subscribes to
  // each and hands what arrives to deliver_input(i, ...) on its LCM thread.
  int input_count() const noexcept { return static_cast<int>(inputs_.size()); }
  const std::string& input_channel(int i) const noexcept { return inputs_[static_cast<std::size_t>(i)].channel; }
  void deliver_input(int i, const std::uint8_t* data, int size, TimeNs now) noexcept;
  std::int64_t input_taken(int i) const noexcept;
  // The input of that channel name, or -1.
  int find_input(std::string_view channel) const noexcept;
  // The device of that registered name, as the type its descriptor makes;
  // null when the configuration has none (tools and tests).
  template <class T>
  T* find(std::string_view name) noexcept {
    const int i = find_device_type(name);
    return i < 0 ? nullptr : dynamic_cast<T*>(devices_[i].get());
  }

 private:
  Hardware() = default;

  std::unique_ptr<Device> devices_[kMaxDeviceTypes];  // at their registry index; null when not enabled
  int polled_[kMaxDeviceTypes] = {};
  int num_polled_ = 0;
  int threaded_[kMaxDeviceTypes] = {};
  int num_threaded_ = 0;
  int workers_[kMaxDeviceTypes] = {};
  int num_workers_ = 0;
  struct Input {
    int device = 0;
    int index = 0;  // among the device's own input channels
    std::string channel;
  };
  std::vector<Input> inputs_;
  DeviceStatus layout_[kMaxDevices];  // names and ids, from describe_devices
  int slot_count_ = 0;
};

}  // namespace rtfuse
