#pragma once
// GPIO lines: edges with their kernel timestamps (an IMU's data-ready line)
// and outputs (status LED, camera trigger).
#include <cstdint>

#include "core/time.hpp"
#include "hal/status.hpp"

namespace rtfuse::hal {

struct GpioEdge {
  TimeNs stamp = 0;  // CLOCK_MONOTONIC ns from the kernel's event timestamp
  bool rising = true;
};

enum class EdgeKind : std::uint8_t { kRising, kFalling, kBoth };

class GpioEdgeSource {
 public:
  virtual ~GpioEdgeSource() = default;
  // Waits up to timeout_ns for the next edge (0: poll). kTimeout if none.
  virtual HalStatus wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept = 0;
  virtual const char* last_error() const noexcept = 0;
};

class GpioOutput {
 public:
  virtual ~GpioOutput() = default;
  virtual HalStatus set(bool high) noexcept = 0;
  virtual const char* last_error() const noexcept = 0;
};

}  // namespace rtfuse::hal
