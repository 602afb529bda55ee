#pragma once
// The constants drivers, the simulator and the filter's helpers share, in one
// place: a driver and the simulated chip it is tested against must convert
// with the same g, and every copy of pi was one more to keep equal.

namespace rtfuse {

constexpr double kPi = 3.14159265358979323846;
// The conventional g (CGPM 1901) MPU datasheets scale their accelerometers by.
constexpr double kStandardGravity = 9.80665;

}  // namespace rtfuse
