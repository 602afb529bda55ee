#pragma once
// Sub-pixel alignment of a small patch (Lucas-Kanade, inverse compositional,
// translation only; Baker and Matthews 2004): the reference patch's
// gradients and 2x2 Gauss-Newton matrix are computed once, then each target
// is sampled bilinearly where the patch currently sits and the shift
// updated until it settles. Both patches are taken with their means
// removed, so a change of exposure between frames does not pull the fit.
//
// Disparity precision sets depth precision: a tenth of a pixel at 5 px of
// disparity is 2 % of the range. The descriptor search finds the integer
// position; this finds the fraction. Fixed-size, no allocation.
#include <cstdint>

#include "vision/plane.hpp"

namespace rtfuse::vision {

class PatchAligner {
 public:
  static constexpr int kHalf = 4;  // a 9 x 9 patch
  static constexpr int kSize = 2 * kHalf + 1;

  // The reference patch centred on pixel (u, v) of ref. False too near the
  // border or on a patch without texture (the fit would be undetermined).
  bool set_reference(const Plane<std::uint8_t>& ref, int u, int v) noexcept;

  // Where the reference sits in target, starting from (u0, v0): true and
  // (*u, *v) when the fit converged within max_shift pixels of the start.
  bool align(const Plane<std::uint8_t>& target, double u0, double v0, double max_shift, double* u,
             double* v) const noexcept;

 private:
  double ref_[kSize * kSize];        // mean removed
  double gu_[kSize * kSize], gv_[kSize * kSize];
  double h_inv_[3] = {0, 0, 0};      // inverse of [[suu, suv], [suv, svv]]: a, b, c = [a b; b c]
};

}  // namespace rtfuse::vision
