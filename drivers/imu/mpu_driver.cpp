#include "drivers/imu/mpu_driver.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "drivers/imu/mpu_registers.hpp"
#include "core/physical_constants.hpp"

namespace rtfuse::drivers {

namespace {

constexpr double kMinTemperatureC = -40.0;  // the chips' operating range
constexpr double kMaxTemperatureC = 85.0;
// After the 100 ms reset delay, PWR_MGMT_1 is polled this many times, 10 ms apart.
constexpr int kResetPolls = 5;
constexpr TimeNs kResetPollNs = 10'000'000;

std::int16_t be16(const std::uint8_t* p) noexcept {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>((p[0] << 8) | p[1]));
}

bool at_full_scale(std::int16_t raw) noexcept { return raw >= 32767 || raw <= -32767; }

bool all_bytes(const std::uint8_t* b, int n, std::uint8_t v) noexcept {
  for (int i = 0; i < n; ++i) {
    if (b[i] != v) return false;
  }
  return true;
}

}  // namespace

const char* to_string(MpuReadStatus s) noexcept {
  switch (s) {
    case MpuReadStatus::kOk: return "ok";
    case MpuReadStatus::kSaturated: return "saturated";
    case MpuReadStatus::kNack: return "nack";
    case MpuReadStatus::kBusError: return "bus error";
    case MpuReadStatus::kTimeout: return "timeout";
    case MpuReadStatus::kIoError: return "i/o error";
    case MpuReadStatus::kFrozen: return "frozen";
    case MpuReadStatus::kImpossible: return "impossible values";
    case MpuReadStatus::kNotInitialised: return "not initialised";
  }
  return "?";
}

MpuDriver::MpuDriver(hal::I2cBus& bus, hal::Clock& clock, const MpuConfig& config) noexcept
    : bus_(bus), clock_(clock), config_(config), model_(config.model) {}

double MpuDriver::sample_rate_hz() const noexcept {
  return mpu_model::sample_rate_hz(config_.dlpf, config_.sample_rate_div);
}

TimeNs MpuDriver::sample_period_ns() const noexcept {
  return static_cast<TimeNs>(std::llround(1e9 / sample_rate_hz()));
}

bool MpuDriver::check_config() noexcept {
  const MpuConfig& c = config_;
  if (c.address != 0x68 && c.address != 0x69) {
    error_.set("mpu config: address 0x%02x is not an MPU address: use 0x68 (AD0 low) or 0x69 (AD0 high)", c.address);
    return false;
  }
  if (c.sample_rate_div < 0 || c.sample_rate_div > 255) {
    error_.set("mpu config: sample_rate_div %d outside 0..255 (rate = 1 kHz / (1 + div))", c.sample_rate_div);
    return false;
  }
  if (c.dlpf < 0 || c.dlpf > 6) {
    error_.set("mpu config: dlpf %d outside 0..6 (3 = 44 Hz accel / 42 Hz gyro)", c.dlpf);
    return false;
  }
  if (mpu_model::gyro_fs_code(c.gyro_full_scale_dps) < 0) {
    error_.set("mpu config: gyro full scale %d dps is not one of 250, 500, 1000, 2000", c.gyro_full_scale_dps);
    return false;
  }
  if (mpu_model::accel_fs_code(c.accel_full_scale_g) < 0) {
    error_.set("mpu config: accel full scale %d g is not one of 2, 4, 8, 16", c.accel_full_scale_g);
    return false;
  }
  const double n = c.base_R_imu.norm();
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3) {
    error_.set("mpu config: base_R_imu is not a unit quaternion (norm %.6f): give w x y z of a rotation", n);
    return false;
  }
  if (c.frozen_reads < 0 || c.failures_before_reinit < 1) {
    error_.set("mpu config: frozen_reads %d must be >= 0 (0 = off) and failures_before_reinit %d >= 1",
               c.frozen_reads, c.failures_before_reinit);
    return false;
  }
  return true;
}

bool MpuDriver::check_identity() noexcept {
  std::uint8_t who = 0;
  const hal::HalStatus s = bus_.read_registers(config_.address, mpu_reg::kWhoAmI, &who, 1);
  if (s != hal::HalStatus::kOk) {
    error_.set("mpu at 0x%02x: reading WHO_AM_I failed (%s: %s): wrong address (AD0 selects 0x68/0x69), wiring, "
               "pull-ups or power",
               config_.address, hal::to_string(s), bus_.last_error());
    return false;
  }
  const MpuModel found = mpu_model::from_who_am_i(who);
  const bool accepted = config_.model == MpuModel::kAuto ? found != MpuModel::kAuto : found == config_.model;
  if (accepted) {
    model_ = found;
    return true;
  }
  const char* expected = config_.model == MpuModel::kAuto ? "0x68, 0x70 or 0x71 (MPU-6050/6500/9250)" : nullptr;
  char expected_buf[48];
  if (expected == nullptr) {
    std::snprintf(expected_buf, sizeof expected_buf, "0x%02x (%s)", mpu_model::who_am_i(config_.model),
                  to_string(config_.model));
    expected = expected_buf;
  }
  if (found != MpuModel::kAuto) {
    error_.set("mpu at 0x%02x: WHO_AM_I reads 0x%02x, expected %s: the chip is an %s: set model to %s or auto",
               config_.address, who, expected, to_string(found), to_string(found));
  } else if (const char* other = mpu_model::other_part_name(who)) {
    error_.set("mpu at 0x%02x: WHO_AM_I reads 0x%02x, expected %s: the chip is an %s, which this driver does not "
               "support (the board is not what it is sold as)",
               config_.address, who, expected, other);
  } else if (who == 0x00 || who == 0xFF) {
    error_.set("mpu at 0x%02x: WHO_AM_I reads 0x%02x, expected %s: bus garbage: check wiring, pull-ups and power",
               config_.address, who, expected);
  } else {
    error_.set("mpu at 0x%02x: WHO_AM_I reads 0x%02x, expected %s: another device at this address: wrong address "
               "or wrong model in the config",
               config_.address, who, expected);
  }
  return false;
}

bool MpuDriver::write(std::uint8_t reg, std::uint8_t value, const char* name) noexcept {
  const hal::HalStatus s = bus_.write_register(config_.address, reg, value);
  if (s == hal::HalStatus::kOk) return true;
  error_.set("mpu at 0x%02x: writing %s (0x%02x) = 0x%02x failed (%s: %s)", config_.address, name, reg, value,
             hal::to_string(s), bus_.last_error());
  return false;
}

bool MpuDriver::reset_chip(TimeNs now) noexcept {
  if (!write(mpu_reg::kPwrMgmt1, mpu_reg::kPwrDeviceReset, "PWR_MGMT_1")) return false;
  TimeNs t = std::max(now, clock_.now()) + mpu_reg::kResetDelayNs;
  clock_.sleep_until(t);
  for (int i = 0; i < kResetPolls; ++i) {
    std::uint8_t pwr = 0;
    const hal::HalStatus s = bus_.read_registers(config_.address, mpu_reg::kPwrMgmt1, &pwr, 1);
    if (s == hal::HalStatus::kOk && (pwr & mpu_reg::kPwrDeviceReset) == 0) return true;
    t += kResetPollNs;
    clock_.sleep_until(t);
  }
  error_.set("mpu at 0x%02x: DEVICE_RESET did not complete within %d ms: the chip is hung; power-cycle it",
             config_.address, static_cast<int>((mpu_reg::kResetDelayNs + kResetPolls * kResetPollNs) / 1'000'000));
  return false;
}

bool MpuDriver::verify(std::uint8_t reg, std::uint8_t expected, std::uint8_t actual, const char* name) noexcept {
  if (expected == actual) return true;
  error_.set("mpu at 0x%02x: %s (0x%02x) reads back 0x%02x after writing 0x%02x: writes are not sticking (another "
             "bus master, or not an MPU)",
             config_.address, name, reg, actual, expected);
  return false;
}

bool MpuDriver::configure() noexcept {
  const auto dlpf = static_cast<std::uint8_t>(config_.dlpf);
  const auto div = static_cast<std::uint8_t>(config_.sample_rate_div);
  gyro_config_ = static_cast<std::uint8_t>(mpu_model::gyro_fs_code(config_.gyro_full_scale_dps) << 3);
  accel_config_ = static_cast<std::uint8_t>(mpu_model::accel_fs_code(config_.accel_full_scale_g) << 3);
  const bool has_accel_config2 = model_ != MpuModel::kMpu6050;
  const std::uint8_t int_pin_cfg = mpu_reg::kIntRdClear;

  if (!write(mpu_reg::kPwrMgmt1, mpu_reg::kPwrClockPll, "PWR_MGMT_1") ||
      !write(mpu_reg::kSmplrtDiv, div, "SMPLRT_DIV") || !write(mpu_reg::kConfig, dlpf, "CONFIG") ||
      !write(mpu_reg::kGyroConfig, gyro_config_, "GYRO_CONFIG") ||
      !write(mpu_reg::kAccelConfig, accel_config_, "ACCEL_CONFIG") ||
      (has_accel_config2 && !write(mpu_reg::kAccelConfig2, dlpf, "ACCEL_CONFIG2")) ||
      !write(mpu_reg::kIntPinCfg, int_pin_cfg, "INT_PIN_CFG") ||
      !write(mpu_reg::kIntEnable, mpu_reg::kDataRdyEn, "INT_ENABLE")) {
    return false;
  }

  std::uint8_t cfg[5] = {};  // SMPLRT_DIV .. ACCEL_CONFIG(2)
  std::uint8_t ints[2] = {};
  std::uint8_t pwr = 0;
  hal::HalStatus s = bus_.read_registers(config_.address, mpu_reg::kSmplrtDiv, cfg, has_accel_config2 ? 5 : 4);
  if (s == hal::HalStatus::kOk) s = bus_.read_registers(config_.address, mpu_reg::kIntPinCfg, ints, 2);
  if (s == hal::HalStatus::kOk) s = bus_.read_registers(config_.address, mpu_reg::kPwrMgmt1, &pwr, 1);
  if (s != hal::HalStatus::kOk) {
    error_.set("mpu at 0x%02x: reading the configuration back failed (%s: %s)", config_.address, hal::to_string(s),
               bus_.last_error());
    return false;
  }
  return verify(mpu_reg::kSmplrtDiv, div, cfg[0], "SMPLRT_DIV") && verify(mpu_reg::kConfig, dlpf, cfg[1], "CONFIG") &&
         verify(mpu_reg::kGyroConfig, gyro_config_, cfg[2], "GYRO_CONFIG") &&
         verify(mpu_reg::kAccelConfig, accel_config_, cfg[3], "ACCEL_CONFIG") &&
         (!has_accel_config2 || verify(mpu_reg::kAccelConfig2, dlpf, cfg[4], "ACCEL_CONFIG2")) &&
         verify(mpu_reg::kIntPinCfg, int_pin_cfg, ints[0], "INT_PIN_CFG") &&
         verify(mpu_reg::kIntEnable, mpu_reg::kDataRdyEn, ints[1], "INT_ENABLE") &&
         verify(mpu_reg::kPwrMgmt1, mpu_reg::kPwrClockPll, pwr, "PWR_MGMT_1");
}

bool MpuDriver::init(TimeNs now) noexcept {
  initialised_ = false;
  error_.clear();
  const bool ok = check_config() && check_identity() && reset_chip(now) && configure();
  if (!ok) {
    ++stats_.init_failures;
    return false;
  }
  base_R_imu_ = config_.base_R_imu.normalized().toRotationMatrix();
  accel_scale_ = kStandardGravity / mpu_model::accel_lsb_per_g(accel_config_ >> 3);
  gyro_scale_ = (kPi / 180.0) / mpu_model::gyro_lsb_per_dps(gyro_config_ >> 3);
  same_count_ = 0;
  stats_.consecutive_failures = 0;
  needs_reinit_ = false;
  initialised_ = true;
  ++stats_.inits;
  return true;
}

MpuReadStatus MpuDriver::fail(MpuReadStatus s) noexcept {
  ++stats_.consecutive_failures;
  if (!needs_reinit_ && stats_.consecutive_failures >= config_.failures_before_reinit) {
    needs_reinit_ = true;
    ++stats_.reinit_requests;
  }
  return s;
}

MpuReadStatus MpuDriver::bus_failure(hal::HalStatus s) noexcept {
  error_.set("mpu at 0x%02x: data read failed (%s: %s)", config_.address, hal::to_string(s), bus_.last_error());
  switch (s) {
    case hal::HalStatus::kNack: ++stats_.nacks; return fail(MpuReadStatus::kNack);
    case hal::HalStatus::kBusError: ++stats_.bus_errors; return fail(MpuReadStatus::kBusError);
    case hal::HalStatus::kTimeout: ++stats_.timeouts; return fail(MpuReadStatus::kTimeout);
    default: ++stats_.io_errors; return fail(MpuReadStatus::kIoError);
  }
}

MpuReadStatus MpuDriver::read(TimeNs stamp, ImuReading* out) noexcept {
  ++stats_.reads;
  if (!initialised_) {
    error_.set("mpu at 0x%02x: read before a successful init()", config_.address);
    return MpuReadStatus::kNotInitialised;
  }
  std::uint8_t b[mpu_reg::kDataBytes];
  const hal::HalStatus s = bus_.read_registers(config_.address, mpu_reg::kAccelXoutH, b, mpu_reg::kDataBytes);
  if (s != hal::HalStatus::kOk) return bus_failure(s);

  if (all_bytes(b, mpu_reg::kDataBytes, 0x00) || all_bytes(b, mpu_reg::kDataBytes, 0xFF)) {
    ++stats_.impossible;
    error_.set("mpu at 0x%02x: data bytes all 0x%02x: bus garbage (chip asleep or lost power?)", config_.address, b[0]);
    return fail(MpuReadStatus::kImpossible);
  }

  if (std::memcmp(b, last_bytes_, sizeof b) == 0) {
    ++same_count_;
  } else {
    std::memcpy(last_bytes_, b, sizeof b);
    same_count_ = 1;
  }
  if (config_.frozen_reads > 0 && same_count_ >= config_.frozen_reads) {
    ++stats_.frozen;
    error_.set("mpu at 0x%02x: the same 14 data bytes %d reads in a row: signal chain frozen", config_.address,
               same_count_);
    return fail(MpuReadStatus::kFrozen);
  }

  std::int16_t raw[7];
  for (int i = 0; i < 7; ++i) raw[i] = be16(b + 2 * i);
  const double temp = mpu_model::temperature_c(model_, raw[3]);
  if (!(temp >= kMinTemperatureC && temp <= kMaxTemperatureC)) {
    ++stats_.impossible;
    error_.set("mpu at 0x%02x: temperature %d C (raw %d) outside -40..85 C: corrupt read or wrong model",
               config_.address, static_cast<int>(temp), raw[3]);
    return fail(MpuReadStatus::kImpossible);
  }

  const bool accel_sat = at_full_scale(raw[0]) || at_full_scale(raw[1]) || at_full_scale(raw[2]);
  const bool gyro_sat = at_full_scale(raw[4]) || at_full_scale(raw[5]) || at_full_scale(raw[6]);
  stats_.consecutive_failures = 0;
  needs_reinit_ = false;
  if (accel_sat || gyro_sat) {
    ++stats_.saturated;
    if (config_.saturation == MpuSaturation::kReject) return MpuReadStatus::kSaturated;
  }

  const Eigen::Vector3d accel_imu(raw[0], raw[1], raw[2]);
  const Eigen::Vector3d gyro_imu(raw[4], raw[5], raw[6]);
  out->stamp = stamp;
  out->accel = base_R_imu_ * (accel_imu * accel_scale_);
  out->gyro = base_R_imu_ * (gyro_imu * gyro_scale_);
  out->temperature_c = temp;
  out->accel_saturated = accel_sat;
  out->gyro_saturated = gyro_sat;
  std::memcpy(out->raw, raw, sizeof raw);
  ++stats_.good_reads;
  return MpuReadStatus::kOk;
}

}  // namespace rtfuse::drivers
