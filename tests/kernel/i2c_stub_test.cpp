// The i2c-dev backend (hal/linux/i2c_dev_bus) and the MPU driver on the
// kernel's i2c-stub (chip_addr=0x68) through i2c-dev: run inside Debian's
// kernel under qemu by kernel_vm.sh.
//
// What i2c-stub is: an SMBus-only adapter ("SMBus stub driver": no plain
// I2C, so no I2C_RDWR) with a 256-byte register file per chip address that
// keeps what is written and auto-increments on block reads. It is a memory,
// not an MPU: DEVICE_RESET stays set until someone clears it, and the data
// registers hold whatever was last written. A "chip" thread here plays those
// two parts of the MPU through its own i2c-dev handle.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <dirent.h>
#include <fstream>
#include <string>
#include <thread>

#include "core/time.hpp"
#include "drivers/imu/mpu_driver.hpp"
#include "drivers/imu/mpu_imu.hpp"
#include "drivers/imu/mpu_registers.hpp"
#include "hal/linux/i2c_dev_bus.hpp"
#include "hal/linux/monotonic_clock.hpp"

namespace {

using rtfuse::hal::HalStatus;
using rtfuse::hal::I2cDevBus;
using rtfuse::hal::I2cRetryPolicy;
using rtfuse::hal::I2cTransferMode;
using rtfuse::drivers::MpuDriver;
using rtfuse::drivers::MpuReadStatus;
namespace reg = rtfuse::drivers::mpu_reg;

constexpr std::uint8_t kAddr = 0x68;

// /dev/i2c-N of the adapter named "SMBus stub driver" ("" if none).
std::string stub_device() {
  DIR* d = ::opendir("/sys/class/i2c-dev");
  if (d == nullptr) return "";
  std::string found;
  while (dirent* e = ::readdir(d)) {
    if (e->d_name[0] == '.') continue;
    std::ifstream f(std::string("/sys/class/i2c-dev/") + e->d_name + "/name");
    std::string name;
    std::getline(f, name);
    if (name == "SMBus stub driver") found = std::string("/dev/") + e->d_name;
  }
  ::closedir(d);
  return found;
}

std::unique_ptr<I2cDevBus> open_stub() {
  const std::string dev = stub_device();
  if (dev.empty()) return nullptr;
  std::string error;
  auto bus = I2cDevBus::open(dev, I2cRetryPolicy{}, &error);
  if (!bus) std::printf("open %s: %s\n", dev.c_str(), error.c_str());
  return bus;
}

void put16(I2cDevBus& bus, std::uint8_t r, std::int16_t v) {
  ASSERT_EQ(bus.write_register(kAddr, r, static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) >> 8)), HalStatus::kOk);
  ASSERT_EQ(bus.write_register(kAddr, static_cast<std::uint8_t>(r + 1), static_cast<std::uint8_t>(v & 0xFF)),
            HalStatus::kOk);
}

// The chip's sampling: a new sample in the data registers every `period`
// (the accelerometer's x low byte counts up, z holds 1 g), as the ADCs
// would latch one, so the frozen detector sees live data.
class SamplePlayer {
 public:
  SamplePlayer(I2cDevBus& bus, std::chrono::milliseconds period)
      : bus_(bus), period_(period), thread_([this] { run(); }) {}
  ~SamplePlayer() {
    stop_ = true;
    thread_.join();
  }

 private:
  void run() {
    std::uint8_t n = 0;
    while (!stop_) {
      (void)bus_.write_register(kAddr, reg::kAccelXoutH + 1, n++);
      std::this_thread::sleep_for(period_);
    }
  }
  I2cDevBus& bus_;
  std::chrono::milliseconds period_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The MPU's DEVICE_RESET: the chip clears the bit (and sleeps) when the
// reset is done. Here within ~2 ms of the write.
class ResetPlayer {
 public:
  explicit ResetPlayer(I2cDevBus& bus) : bus_(bus), thread_([this] { run(); }) {}
  ~ResetPlayer() {
    stop_ = true;
    thread_.join();
  }
  int resets() const { return resets_; }

 private:
  void run() {
    while (!stop_) {
      std::uint8_t pwr = 0;
      if (bus_.read_registers(kAddr, reg::kPwrMgmt1, &pwr, 1) == HalStatus::kOk && (pwr & reg::kPwrDeviceReset)) {
        (void)bus_.write_register(kAddr, reg::kPwrMgmt1, reg::kPwrSleep);
        ++resets_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  I2cDevBus& bus_;
  std::atomic<bool> stop_{false};
  std::atomic<int> resets_{0};
  std::thread thread_;
};

TEST(I2cStub, SmbusOnlyAdapterIsOpenedInSmbusMode) {
  auto bus = open_stub();
  ASSERT_NE(bus, nullptr) << "no i2c-stub adapter under /sys/class/i2c-dev";
  EXPECT_EQ(bus->mode(), I2cTransferMode::kSmbus);
  std::printf("%s: %s\n", bus->name().c_str(), to_string(bus->mode()));
}

TEST(I2cStub, BlockReadsLongerThan32BytesReadSuccessiveRegisters) {
  auto bus = open_stub();
  ASSERT_NE(bus, nullptr);
  for (int r = 0; r < 48; ++r) {
    ASSERT_EQ(bus->write_register(kAddr, static_cast<std::uint8_t>(0x80 + r), static_cast<std::uint8_t>(0x40 + r)),
              HalStatus::kOk);
  }
  std::uint8_t buf[64] = {};
  ASSERT_EQ(bus->read_registers(kAddr, 0x80, buf, 48), HalStatus::kOk) << bus->last_error();
  for (int i = 0; i < 48; ++i) EXPECT_EQ(buf[i], 0x40 + i) << i;
  ASSERT_EQ(bus->read_registers(kAddr, 0x85, buf, 1), HalStatus::kOk);
  EXPECT_EQ(buf[0], 0x45);
}

TEST(I2cStub, AbsentAddressFailsWithTheKernelsErrno) {
  auto bus = open_stub();
  ASSERT_NE(bus, nullptr);
  std::uint8_t b = 0;
  const HalStatus s = bus->read_registers(0x69, reg::kWhoAmI, &b, 1);
  std::printf("read at 0x69: %s: %s\n", rtfuse::hal::to_string(s), bus->last_error());
  // i2c-stub answers ENODEV for an address with no chip (real adapters say
  // ENXIO, a NACK, per the kernel's i2c fault codes); the backend reads
  // ENODEV as a device gone and does not retry.
  EXPECT_EQ(s, HalStatus::kClosed);
  EXPECT_NE(std::string(bus->last_error()).find("addr 0x69 reg 0x75 failed on attempt 1 of 3: No such device"),
            std::string::npos);

  rtfuse::hal::MonotonicClock clock;
  rtfuse::drivers::MpuConfig cfg;
  cfg.address = 0x69;
  MpuDriver mpu(*bus, clock, cfg);
  EXPECT_FALSE(mpu.init(clock.now()));
  std::printf("driver at 0x69: %s\n", mpu.error());
  EXPECT_NE(std::string(mpu.error()).find("mpu at 0x69: reading WHO_AM_I failed"), std::string::npos) << mpu.error();
}

TEST(I2cStub, MpuDriverInitialisesAndReadsThroughI2cDev) {
  auto bus = open_stub();
  auto chip_bus = open_stub();
  ASSERT_NE(bus, nullptr);
  ASSERT_NE(chip_bus, nullptr);
  // An MPU-6050 at rest, z up: +1 g on z at +-4 g (8192 LSB/g), 10 deg/s on
  // the gyro's x at +-500 deg/s (65.5 LSB/(deg/s)), 25.0 C.
  ASSERT_EQ(bus->write_register(kAddr, reg::kWhoAmI, reg::kWhoAmI6050), HalStatus::kOk);
  put16(*bus, reg::kAccelXoutH + 0, 0);
  put16(*bus, reg::kAccelXoutH + 2, 0);
  put16(*bus, reg::kAccelXoutH + 4, 8192);
  put16(*bus, reg::kAccelXoutH + 6, -3920);
  put16(*bus, reg::kAccelXoutH + 8, 655);
  put16(*bus, reg::kAccelXoutH + 10, 0);
  put16(*bus, reg::kAccelXoutH + 12, -131);
  ASSERT_EQ(bus->write_register(kAddr, reg::kPwrMgmt1, reg::kPwrSleep), HalStatus::kOk);

  rtfuse::hal::MonotonicClock clock;
  rtfuse::drivers::MpuConfig cfg;
  cfg.gyro_full_scale_dps = 500;
  cfg.accel_full_scale_g = 4;
  cfg.frozen_reads = 5;
  MpuDriver mpu(*bus, clock, cfg);
  {
    ResetPlayer chip(*chip_bus);
    ASSERT_TRUE(mpu.init(clock.now())) << mpu.error();
    EXPECT_EQ(chip.resets(), 1);
  }
  EXPECT_EQ(mpu.model(), rtfuse::drivers::MpuModel::kMpu6050);
  // The configuration went to the registers (i2c-stub keeps them).
  std::uint8_t cfgregs[4] = {};
  ASSERT_EQ(bus->read_registers(kAddr, reg::kSmplrtDiv, cfgregs, 4), HalStatus::kOk);
  EXPECT_EQ(cfgregs[0], 9);       // SMPLRT_DIV: 100 Hz
  EXPECT_EQ(cfgregs[2], 1 << 3);  // GYRO_CONFIG FS_SEL 1: +-500 deg/s
  EXPECT_EQ(cfgregs[3], 1 << 3);  // ACCEL_CONFIG AFS_SEL 1: +-4 g

  rtfuse::drivers::ImuReading r;
  ASSERT_EQ(mpu.read(clock.now(), &r), MpuReadStatus::kOk) << mpu.error();
  EXPECT_NEAR(r.accel.z(), 9.80665, 1e-9);
  EXPECT_NEAR(r.accel.x(), 0.0, 1e-12);
  EXPECT_NEAR(r.gyro.x(), 10.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(r.gyro.z(), -2.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(r.temperature_c, 25.0, 0.01);
  EXPECT_FALSE(r.accel_saturated);
  std::printf("read: accel %.5f %.5f %.5f m/s^2, gyro %.5f %.5f %.5f rad/s, %.3f C\n", r.accel.x(), r.accel.y(),
              r.accel.z(), r.gyro.x(), r.gyro.y(), r.gyro.z(), r.temperature_c);

  // The stub's data never changes: the fifth identical read in a row is a
  // frozen signal chain; a changed sample is good again.
  int first_frozen = 0;
  for (int i = 2; i <= 8 && first_frozen == 0; ++i) {
    if (mpu.read(clock.now(), &r) == MpuReadStatus::kFrozen) first_frozen = i;
  }
  EXPECT_EQ(first_frozen, cfg.frozen_reads);
  EXPECT_GE(mpu.stats().frozen, 1);
  put16(*bus, reg::kAccelXoutH + 0, 17);
  ASSERT_EQ(mpu.read(clock.now(), &r), MpuReadStatus::kOk) << mpu.error();
  EXPECT_NEAR(r.accel.x(), 17 * 9.80665 / 8192.0, 1e-9);

  // Full scale on the accelerometer's y is flagged.
  put16(*bus, reg::kAccelXoutH + 2, 32767);
  ASSERT_EQ(mpu.read(clock.now(), &r), MpuReadStatus::kOk);
  EXPECT_TRUE(r.accel_saturated);
  EXPECT_EQ(mpu.stats().saturated, 1);
}

TEST(I2cStub, MpuImuPollsWithoutADataReadyLine) {
  // Debian's kernel has no gpio-sim or gpio-mockup, so the data-ready path
  // is covered through the mock HAL only; the polling mode runs here on the
  // real i2c-dev interface: no line, one read per sample period.
  auto bus = open_stub();
  auto chip_bus = open_stub();
  ASSERT_NE(bus, nullptr);
  ASSERT_NE(chip_bus, nullptr);
  ASSERT_EQ(bus->write_register(kAddr, reg::kWhoAmI, reg::kWhoAmI6050), HalStatus::kOk);
  put16(*bus, reg::kAccelXoutH + 4, 8192);
  put16(*bus, reg::kAccelXoutH + 6, -3920);
  rtfuse::hal::MonotonicClock clock;
  rtfuse::drivers::MpuImuConfig cfg;  // 100 Hz (SMPLRT_DIV 9), polled at the sample rate
  rtfuse::drivers::MpuImu imu(cfg, *bus, nullptr, clock);
  ASSERT_TRUE(imu.polling());
  {
    ResetPlayer reset(*chip_bus);
    ASSERT_TRUE(imu.start()) << imu.error();
  }
  SamplePlayer chip(*chip_bus, std::chrono::milliseconds(5));
  const rtfuse::TimeNs t0 = clock.now();
  int samples = 0;
  rtfuse::TimeNs first = 0, last = 0;
  while (clock.now() - t0 < 1'000'000'000) {
    rtfuse::drivers::ImuMeasurement m;
    const rtfuse::drivers::StepResult r = imu.step(100'000'000, &m);
    if (r != rtfuse::drivers::StepResult::kSample) continue;
    if (samples++ == 0) first = m.stamp;
    last = m.stamp;
    EXPECT_NEAR(m.linear_acceleration.z(), 9.80665, 0.01);
  }
  const double rate = (samples - 1) / ((last - first) / 1e9);
  const rtfuse::drivers::MpuImuStats st = imu.stats();
  std::printf("polling: %d samples in 1 s (%.1f Hz), %lld reads, %lld frozen, %lld faults\n", samples, rate,
              static_cast<long long>(st.reads), static_cast<long long>(st.frozen),
              static_cast<long long>(st.nacks + st.bus_errors + st.io_errors));
  // 100 Hz on the monotonic clock; TCG and the shared machine may cost a few.
  EXPECT_GE(samples, 80);
  EXPECT_NEAR(rate, 100.0, 10.0);
  EXPECT_EQ(st.frozen, 0);
  EXPECT_EQ(st.nacks + st.bus_errors + st.io_errors, 0);
}

TEST(I2cStub, ResetThatNeverCompletesIsReported) {
  auto bus = open_stub();
  ASSERT_NE(bus, nullptr);
  ASSERT_EQ(bus->write_register(kAddr, reg::kWhoAmI, reg::kWhoAmI6050), HalStatus::kOk);
  rtfuse::hal::MonotonicClock clock;
  MpuDriver mpu(*bus, clock, rtfuse::drivers::MpuConfig{});
  // No chip thread: DEVICE_RESET stays set, as on a hung chip.
  EXPECT_FALSE(mpu.init(clock.now()));
  EXPECT_NE(std::string(mpu.error()).find("DEVICE_RESET did not complete"), std::string::npos) << mpu.error();
}

}  // namespace
