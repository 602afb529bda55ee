#pragma once
// Angle normalisation shared by the filter (yaw innovations) and config.
#include <cmath>

#include "core/physical_constants.hpp"

namespace rtfuse::geometry {

using rtfuse::kPi;
constexpr double kTwoPi = 2.0 * kPi;

// Wraps to [-pi, pi). std::remainder is exact for every finite input, so large
// multiples of 2*pi keep their fractional part (a loop of += 2*pi would
// accumulate rounding and never end for huge values; fmod + shift loses the
// sign symmetry). Non-finite input gives NaN.
inline double wrap_angle(double a) noexcept {
  // Filter angles are nearly always in range already: skip the libm call
  // (it was ~8 % of a prediction). NaN fails the test and takes the slow path.
  if (a >= -kPi && a < kPi) return a;
  const double r = std::remainder(a, kTwoPi);  // in [-pi, pi]
  return r >= kPi ? r - kTwoPi : r;
}

}  // namespace rtfuse::geometry
