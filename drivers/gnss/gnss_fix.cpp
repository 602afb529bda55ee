#include "drivers/gnss/gnss_fix.hpp"

namespace rtfuse::drivers {

const char* to_string(GnssSolution s) noexcept {
  switch (s) {
    case GnssSolution::kNone: return "no fix";
    case GnssSolution::kDeadReckoning: return "dead reckoning";
    case GnssSolution::kAutonomous: return "autonomous";
    case GnssSolution::kDifferential: return "differential";
    case GnssSolution::kRtkFloat: return "RTK float";
    case GnssSolution::kRtkFixed: return "RTK fixed";
  }
  return "?";
}

}  // namespace rtfuse::drivers
