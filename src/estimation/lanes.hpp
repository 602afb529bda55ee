#pragma once
// Two doubles side by side, the width both targets share: an SSE2 register
// on x86-64 and a NEON register on aarch64. Written with GCC's vector
// extension (GCC and Clang both take it) rather than intrinsics so one source
// serves both; the build turns FMA contraction off, so a lane's multiply and
// add round exactly as the scalar operations would, and x86-64 and aarch64
// compute the same bits. Eigen's own vectorisation stays off in the portable
// build because its kernels reorder sums differently per instruction set.
#include <cstring>

namespace rtfuse::est::lanes {

using D2 = double __attribute__((vector_size(16)));

// Through memcpy: the rows and columns these read are 8-byte aligned only
// (a 15-double state vector, a column of a padded matrix at any offset).
inline D2 load(const double* p) noexcept {
  D2 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, D2 v) noexcept { std::memcpy(p, &v, sizeof v); }
inline D2 splat(double s) noexcept { return D2{s, s}; }

}  // namespace rtfuse::est::lanes
