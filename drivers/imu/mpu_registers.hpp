#pragma once
// InvenSense MPU-6050 / MPU-6500 / MPU-9250 registers and constants, from the
// register maps and product specifications (RM-MPU-6000A rev 4.2, RM-MPU-6500
// rev 2.1, RM-MPU-9250A rev 1.6, PS-MPU-6000A rev 3.4, PS-MPU-6500A rev 1.1).
// Only the accel/gyro part the three chips share, plus ACCEL_CONFIG2 of the
// 6500/9250. The driver owns its copy: drivers never include hal/mock.
#include <cstdint>

namespace rtfuse::drivers::mpu_reg {

constexpr std::uint8_t kSmplrtDiv = 0x19;
constexpr std::uint8_t kConfig = 0x1A;        // EXT_SYNC_SET 5:3, DLPF_CFG 2:0
constexpr std::uint8_t kGyroConfig = 0x1B;    // FS_SEL 4:3
constexpr std::uint8_t kAccelConfig = 0x1C;   // AFS_SEL 4:3
constexpr std::uint8_t kAccelConfig2 = 0x1D;  // 6500/9250 only: ACCEL_FCHOICE_B 3, A_DLPF_CFG 2:0
constexpr std::uint8_t kIntPinCfg = 0x37;
constexpr std::uint8_t kIntEnable = 0x38;
constexpr std::uint8_t kIntStatus = 0x3A;
constexpr std::uint8_t kAccelXoutH = 0x3B;  // 14 bytes: accel xyz, temp, gyro xyz (big-endian)
constexpr std::uint8_t kPwrMgmt1 = 0x6B;
constexpr std::uint8_t kWhoAmI = 0x75;

constexpr int kDataBytes = 14;

// PWR_MGMT_1
constexpr std::uint8_t kPwrDeviceReset = 0x80;
constexpr std::uint8_t kPwrSleep = 0x40;
// CLKSEL = 1: PLL on the X gyro (6050), "best available, PLL if ready" (6500/9250).
// Both are the recommended clock: the internal 8/20 MHz oscillator drifts.
constexpr std::uint8_t kPwrClockPll = 0x01;

// INT_PIN_CFG
constexpr std::uint8_t kIntLatchEn = 0x20;  // hold the pin until cleared (else a 50 us pulse)
constexpr std::uint8_t kIntRdClear = 0x10;  // any read clears INT_STATUS (else only reading INT_STATUS)

// INT_ENABLE / INT_STATUS
constexpr std::uint8_t kDataRdyEn = 0x01;

// WHO_AM_I values. AD0 does not show in WHO_AM_I: a 6050 at 0x69 still reads 0x68.
constexpr std::uint8_t kWhoAmI6050 = 0x68;
constexpr std::uint8_t kWhoAmI6500 = 0x70;
constexpr std::uint8_t kWhoAmI9250 = 0x71;
// Parts often found on boards sold as "MPU-9250" or "MPU-6050" modules: named
// in the WHO_AM_I error so the fix (it is another chip) is obvious.
constexpr std::uint8_t kWhoAmI9255 = 0x73;
constexpr std::uint8_t kWhoAmIIcm20602 = 0x12;
constexpr std::uint8_t kWhoAmIIcm20689 = 0x98;

// The product specification asks for 100 ms after DEVICE_RESET before the
// registers can be written.
constexpr std::int64_t kResetDelayNs = 100'000'000;

}  // namespace rtfuse::drivers::mpu_reg
