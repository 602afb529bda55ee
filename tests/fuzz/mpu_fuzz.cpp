// The MPU driver's register decoding: WHO_AM_I, the configuration read-back
// and the 14-byte data burst, from a chip whose answers the input writes.
// The chip keeps what is written (so configuration can succeed, as on a
// real part) while the input supplies WHO_AM_I, every data burst, and NACKs,
// bus errors and timeouts at any transfer.
// Property: init succeeds or says why; a kOk reading is finite, within the
// configured full scale and the chip's temperature range; the counters add
// up to the reads made.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "drivers/imu/mpu_driver.hpp"
#include "drivers/imu/mpu_registers.hpp"
#include "fuzz_check.hpp"
#include "hal/mock/mock_i2c_bus.hpp"
#include "hal/mock/sim_clock.hpp"

using namespace rtfuse::drivers;
using rtfuse::hal::HalStatus;

namespace {

class ScriptedChip final : public rtfuse::hal::mock::I2cDevice {
 public:
  explicit ScriptedChip(FuzzedDataProvider& in) : in_(in) {}

  HalStatus i2c_read(std::uint8_t reg, std::uint8_t* buf, int n) noexcept override {
    if (const HalStatus s = fault(); s != HalStatus::kOk) return s;
    for (int i = 0; i < n; ++i) {
      const int r = (reg + i) & 0xFF;
      const bool data = r >= mpu_reg::kAccelXoutH && r < mpu_reg::kAccelXoutH + mpu_reg::kDataBytes;
      if (r == mpu_reg::kWhoAmI) {
        const std::uint8_t ids[] = {mpu_reg::kWhoAmI6050, mpu_reg::kWhoAmI6500, mpu_reg::kWhoAmI9250,
                                    in_.ConsumeIntegral<std::uint8_t>()};
        buf[i] = ids[in_.ConsumeIntegralInRange(0, 3)];
      } else if (data || r == mpu_reg::kIntStatus) {
        buf[i] = in_.ConsumeIntegral<std::uint8_t>();
      } else {
        buf[i] = regs_[r];
      }
    }
    return HalStatus::kOk;
  }
  HalStatus i2c_write(std::uint8_t reg, std::uint8_t value) noexcept override {
    if (const HalStatus s = fault(); s != HalStatus::kOk) return s;
    // DEVICE_RESET clears itself and leaves the chip asleep.
    regs_[reg] = reg == mpu_reg::kPwrMgmt1 && (value & mpu_reg::kPwrDeviceReset) ? mpu_reg::kPwrSleep : value;
    return HalStatus::kOk;
  }

 private:
  HalStatus fault() {
    const std::uint8_t f = in_.ConsumeIntegral<std::uint8_t>();
    if (f < 240) return HalStatus::kOk;
    const HalStatus faults[] = {HalStatus::kNack, HalStatus::kBusError, HalStatus::kTimeout};
    return faults[f % 3];
  }
  FuzzedDataProvider& in_;
  std::uint8_t regs_[256] = {};
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  MpuConfig config;
  const MpuModel models[] = {MpuModel::kAuto, MpuModel::kMpu6050, MpuModel::kMpu6500, MpuModel::kMpu9250};
  config.model = models[in.ConsumeIntegralInRange(0, 3)];
  const int gyro[] = {250, 500, 1000, 2000};
  const int accel[] = {2, 4, 8, 16};
  config.gyro_full_scale_dps = gyro[in.ConsumeIntegralInRange(0, 3)];
  config.accel_full_scale_g = accel[in.ConsumeIntegralInRange(0, 3)];
  config.saturation = in.ConsumeBool() ? MpuSaturation::kFlag : MpuSaturation::kReject;
  config.frozen_reads = in.ConsumeIntegralInRange(0, 5);

  ScriptedChip chip(in);
  rtfuse::hal::mock::MockI2cBus bus;
  FUZZ_CHECK(bus.attach(config.address, chip), "the chip attaches");
  rtfuse::hal::mock::SimClock clock(1'000'000'000);
  MpuDriver driver(bus, clock, config);
  rtfuse::TimeNs stamp = clock.now();
  std::int64_t reads = 0;
  for (int attempt = 0; attempt < 64 && in.remaining_bytes() > 0; ++attempt) {
    if (!driver.initialised() || driver.needs_reinit()) {
      if (!driver.init(clock.now())) {
        FUZZ_CHECK(std::strlen(driver.error()) > 0, "a failed init says why");
        continue;
      }
    }
    ImuReading r;
    stamp += 10'000'000;
    const MpuReadStatus s = driver.read(stamp, &r);
    ++reads;
    FUZZ_CHECK(to_string(s) != nullptr, "every status has a name");
    if (s != MpuReadStatus::kOk) continue;
    FUZZ_CHECK(r.stamp == stamp, "the reading carries its stamp");
    FUZZ_CHECK(r.accel.allFinite() && r.gyro.allFinite() && std::isfinite(r.temperature_c), "finite");
    const double slack = 1.0 + 1e-9;
    FUZZ_CHECK(r.accel.lpNorm<Eigen::Infinity>() <= driver.accel_full_scale_mps2() * std::sqrt(3.0) * slack,
               "accel within full scale");
    FUZZ_CHECK(r.gyro.lpNorm<Eigen::Infinity>() <= driver.gyro_full_scale_rad_s() * std::sqrt(3.0) * slack,
               "gyro within full scale");
    FUZZ_CHECK(r.temperature_c >= -40.0 && r.temperature_c <= 85.0, "temperature in the chip's range");
  }
  const MpuDriverStats& st = driver.stats();
  FUZZ_CHECK(st.reads == reads, "every read counted");
  FUZZ_CHECK(st.good_reads <= st.reads, "good reads among reads");
  return 0;
}
