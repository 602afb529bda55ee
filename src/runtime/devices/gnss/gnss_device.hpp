#pragma once
// A GNSS receiver as a thread device: each step waits on the serial port for
// bytes, turns complete epochs into navsat samples for the sensor with
// source = "gnss" (stamped at their epoch: the receive time less the
// configured latency), and reports the receiver's health through a SeqLatch.
// A port that went away (a USB receiver unplugged) is reopened with a
// backoff, as the camera is.
#include <atomic>
#include <memory>
#include <string>

#include "core/seq_cell.hpp"
#include "drivers/gnss/gnss_receiver.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/device_buses.hpp"
#include "runtime/fusion/fusion_core.hpp"

namespace rtfuse {

drivers::GnssReceiverConfig gnss_driver_config(const GnssSection& g) noexcept;

// The driver's fix as the filter's navsat sample (NavSatFix semantics): a
// dead-reckoned epoch is no fix; an altitude the receiver held (2-D fix)
// gets a vertical variance that says it is unknown.
void gnss_fix_to_sample(const drivers::GnssFix& fix, TimeNs latency_ns, est::SensorSample* out) noexcept;

// The receiver's epochs and faults (drivers::GnssReceiverStats); hdop_milli
// the last epoch's HDOP x1000 (-1 unknown).
extern const char* const kGnssKeys[14];

class GnssDevice final : public Device {
 public:
  // The configuration is the core's; buses.serial and buses.clock are required.
  static std::unique_ptr<GnssDevice> create(const DeviceBuses& buses, FusionCore& core, int device_slot,
                                            std::string* error);

  void step(TimeNs timeout_ns) noexcept override;
  int sensor() const noexcept override { return sensor_; }
  std::int64_t samples() const noexcept override { return samples_.load(std::memory_order_acquire); }
  void fill_snapshot(Snapshot& s) noexcept override;

  const drivers::GnssReceiver& receiver() const noexcept { return *receiver_; }

 private:
  GnssDevice(const DeviceBuses& buses, FusionCore& core, int device_slot);
  // The port is gone: reopen it when the backoff allows, else wait for that.
  void recover(TimeNs timeout_ns) noexcept;

  struct Health {
    drivers::GnssReceiverStats stats;
    drivers::GnssHealth state = drivers::GnssHealth::kStarting;
    std::int64_t reopens = 0;
    int satellites = 0;
    double hdop = -1.0;
    DeviceMessage error;  // kept after the receiver recovers
  };

  FusionCore& core_;
  hal::SerialPort& port_;
  hal::Clock& clock_;
  int sensor_ = -1;
  int slot_ = -1;
  TimeNs latency_ns_ = 0;
  TimeNs backoff_min_ns_ = 0;
  TimeNs backoff_max_ns_ = 0;
  std::unique_ptr<drivers::GnssReceiver> receiver_;
  bool port_open_ = true;
  TimeNs backoff_ns_ = 0;
  TimeNs next_reopen_ = 0;
  static constexpr int kFixesPerStep = 4;
  drivers::GnssFix fixes_[kFixesPerStep];
  est::SensorSample sample_;
  Health scratch_;
  SeqLatch<Health> health_;
  std::atomic<std::int64_t> samples_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

}  // namespace rtfuse
