#pragma once
// UBX-NAV-PVT (class 0x01, id 0x07): a u-blox receiver's whole navigation
// solution in one message, 92 bytes (u-blox 8 and later; 84 on u-blox 7,
// which lacks the fields after pDOP). A fix is kept as one only when
// fixType is 2-D, 3-D or GNSS + dead reckoning, gnssFixOK is set and
// invalidLlh is not (u-blox: otherwise the position must not be used).
// Covariance from hAcc and vAcc (the receiver's 1-sigma estimates),
// diagonal known, as the ROS u-blox driver does.
#include <cstddef>
#include <cstdint>

#include "drivers/gnss/gnss_fix.hpp"

namespace rtfuse::drivers {

constexpr std::uint8_t kUbxClassNav = 0x01;
constexpr std::uint8_t kUbxIdNavPvt = 0x07;

// Fills *fix (stamp included) from a NAV-PVT payload; false with *why when
// the payload cannot be one (its length) or holds impossible values
// (latitude beyond 90 degrees, a month 13...).
bool decode_nav_pvt(const std::uint8_t* payload, std::size_t length, TimeNs stamp, GnssFix* fix,
                    const char** why) noexcept;

}  // namespace rtfuse::drivers
