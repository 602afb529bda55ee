#pragma once
// An MPU-6050/6500/9250 as a sensor: the register driver, its data-ready line
// (or polling at a fixed rate without one), the attitude filter and recovery,
// producing sensor_msgs/Imu-like measurements in base_link.
//
// step() is what a sensor thread calls in a loop: it waits for one data-ready
// edge (or sleeps until the next poll), reads, filters and returns a status;
// faults are counted and end in a re-initialisation of the chip, never in a
// stop. Nothing in step() allocates; the re-init path sleeps (chip reset).
//
// Covariances: angular velocity and linear acceleration from MpuNoise (the
// datasheet density over the DLPF bandwidth, or configured variances),
// orientation from the attitude filter's model (attitude_filter.hpp).
//
// Gyro bias: the attitude filter estimates roll/pitch's from gravity; with
// `stillness` enabled all three axes, yaw's included, are learnt while the
// robot stands still (stillness_bias.hpp) and removed from angular_velocity
// and from the yaw integration. Once a standstill taught it, the yaw-rate
// variance (angular_velocity_cov(2,2)) carries what is left of the z bias
// error (averaging noise plus drift since the last standstill) on top of
// the noise. Before that it is the noise alone, as sensor_msgs/Imu drivers
// report it; the unestimated bias is then only in the orientation's yaw
// variance (AttitudeConfig::yaw_bias_sigma).
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/time.hpp"
#include "drivers/imu/attitude_filter.hpp"
#include "drivers/imu/error_text.hpp"
#include "drivers/imu/mpu_driver.hpp"
#include "drivers/imu/mpu_noise.hpp"
#include "hal/clock.hpp"
#include "hal/gpio.hpp"
#include "hal/i2c_bus.hpp"

namespace rtfuse::drivers {

struct MpuImuConfig {
  MpuConfig chip;
  AttitudeConfig attitude;  // its noise fields are replaced by the `noise` model's
  StillnessConfig stillness;  // bias learning at standstill; on by default
  MpuNoiseConfig noise;
  // Without a data-ready line: reads per second; <= 0 takes the chip's
  // sample rate. Polling faster than the chip repeats samples (and trips the
  // frozen detector), so keep it at or below the sample rate.
  double poll_rate_hz = 0.0;
  // Edge waits that time out add up; more than this many sample periods
  // without an edge is one missing edge.
  double missing_edge_periods = 3.0;
  // Consecutive missing edges before the chip is initialised again.
  int missing_edges_before_reinit = 3;
  // After a failed re-init, the next attempt waits this long.
  TimeNs reinit_backoff_ns = 1'000'000'000;
};

struct ImuMeasurement {
  TimeNs stamp = 0;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // world(gravity-aligned, z up) <- base_link
  Eigen::Matrix3d orientation_cov = Eigen::Matrix3d::Zero();        // roll, pitch, yaw
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();       // rad/s, bias-corrected
  Eigen::Matrix3d angular_velocity_cov = Eigen::Matrix3d::Zero();
  Eigen::Vector3d linear_acceleration = Eigen::Vector3d::Zero();    // m/s^2, gravity included
  Eigen::Matrix3d linear_acceleration_cov = Eigen::Matrix3d::Zero();
  bool has_orientation = false;
  bool has_angular_velocity = false;
  bool has_linear_acceleration = false;
  double temperature_c = 0.0;
};

enum class StepResult : std::uint8_t {
  kSample,          // *out holds a new measurement
  kTimeout,         // no edge within the timeout (maybe counted as a missing edge)
  kDropped,         // an edge arrived but gave no sample (out of order, falling edge, saturated under kReject)
  kFault,           // the read or the edge wait failed; counted, recovery follows after the threshold
  kReinitialised,   // the chip was initialised again in this call (no sample)
  kDown,            // the chip is not initialised and re-init failed or is backing off
};

const char* to_string(StepResult r) noexcept;

struct MpuImuStats {
  std::int64_t reads = 0;
  std::int64_t samples = 0;  // measurements delivered
  std::int64_t nacks = 0;
  std::int64_t bus_errors = 0;
  std::int64_t timeouts = 0;  // I2C timeouts
  std::int64_t io_errors = 0;
  std::int64_t frozen = 0;
  std::int64_t saturated = 0;
  std::int64_t impossible = 0;
  std::int64_t edge_timeouts = 0;  // wait_edge calls that timed out
  std::int64_t missing_edges = 0;
  std::int64_t out_of_order_edges = 0;
  std::int64_t ignored_edges = 0;  // falling edges
  std::int64_t edge_errors = 0;    // wait_edge failures other than a timeout
  std::int64_t reinits = 0;        // successful re-initialisations after start()
  std::int64_t reinit_failures = 0;
  std::int64_t filter_rejects = 0;  // samples the attitude filter rejected (non-finite, dt <= 0)
  std::int64_t filter_gap_reinits = 0;
};

class MpuImu {
 public:
  // edges == nullptr: no data-ready line, poll with the clock.
  MpuImu(const MpuImuConfig& config, hal::I2cBus& bus, hal::GpioEdgeSource* edges, hal::Clock& clock) noexcept;

  // Initialises the chip; false with error() on failure (step() then retries
  // after reinit_backoff_ns).
  bool start() noexcept;
  StepResult step(TimeNs edge_timeout_ns, ImuMeasurement* out) noexcept;

  MpuImuStats stats() const noexcept;
  const char* error() const noexcept;
  const MpuDriver& driver() const noexcept { return driver_; }
  const AttitudeFilter& filter() const noexcept { return filter_; }
  const MpuNoise& noise() const noexcept { return noise_; }
  bool polling() const noexcept { return edges_ == nullptr; }

 private:
  StepResult reinit() noexcept;
  StepResult while_down(TimeNs edge_timeout_ns) noexcept;
  StepResult on_edge_timeout(TimeNs edge_timeout_ns) noexcept;
  // The stamp of the next sample, or a result when there is none.
  bool next_stamp(TimeNs edge_timeout_ns, TimeNs* stamp, StepResult* result) noexcept;
  void after_init() noexcept;
  StepResult deliver(const ImuReading& r, ImuMeasurement* out) noexcept;

  MpuImuConfig config_;
  MpuDriver driver_;
  hal::GpioEdgeSource* edges_;
  hal::Clock& clock_;
  AttitudeFilter filter_;
  MpuNoise noise_;
  Eigen::Matrix3d gyro_cov_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d accel_cov_ = Eigen::Matrix3d::Zero();
  TimeNs period_ns_ = 0;
  TimeNs poll_period_ns_ = 0;
  TimeNs next_poll_ = 0;
  TimeNs waited_ns_ = 0;
  int consecutive_missing_ = 0;
  int consecutive_out_of_order_ = 0;
  bool have_edge_ = false;
  TimeNs last_edge_ = 0;
  bool have_sample_ = false;
  TimeNs last_sample_ = 0;
  TimeNs next_reinit_ = 0;
  bool started_ = false;
  MpuImuStats stats_;
  ErrorText error_;
  const char* last_error_;  // error_ or the driver's, whichever failed last
};

}  // namespace rtfuse::drivers
