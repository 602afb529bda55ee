#pragma once
// How a wheeled base turns: the two wheels of a differential drive, or the
// four of a skid steer that scrub sideways in a turn. The wheel odometry
// computes with it; the simulator's base moves by it.
#include <cstdint>

namespace rtfuse::drivers {

enum class DriveKinematics : std::uint8_t { kDifferential, kSkidSteer };

}  // namespace rtfuse::drivers
