#include "vision/patch_aligner.hpp"

#include <cmath>

namespace rtfuse::vision {
namespace {

constexpr int kIterations = 8;
constexpr double kConverged = 0.01;  // px

// The kSize x kSize patch centred on (u, v), sampled bilinearly, into
// out; returns its mean. Every pixel of the patch shares the fraction of
// (u, v), so the weights are taken once (per pixel, the floor and the row
// look-up cost more than the arithmetic). The caller keeps the patch and
// one more column and row inside.
inline double sample_patch(const Plane<std::uint8_t>& p, double u, double v, double* out) noexcept {
  const int iu = static_cast<int>(std::floor(u)), iv = static_cast<int>(std::floor(v));
  const double fu = u - iu, fv = v - iv;
  double sum = 0.0;
  const std::uint8_t* r1 = p.row(iv - PatchAligner::kHalf) + iu - PatchAligner::kHalf;
  for (int j = 0, k = 0; j < PatchAligner::kSize; ++j) {
    const std::uint8_t* r0 = r1;
    r1 = r0 + p.stride();
    for (int i = 0; i < PatchAligner::kSize; ++i, ++k) {
      const double top = r0[i] + fu * (r0[i + 1] - r0[i]);
      const double bottom = r1[i] + fu * (r1[i + 1] - r1[i]);
      sum += out[k] = top + fv * (bottom - top);
    }
  }
  return sum / (PatchAligner::kSize * PatchAligner::kSize);
}

}  // namespace

bool PatchAligner::set_reference(const Plane<std::uint8_t>& ref, int u, int v) noexcept {
  if (u - kHalf - 1 < 0 || v - kHalf - 1 < 0 || u + kHalf + 1 >= ref.width() || v + kHalf + 1 >= ref.height()) {
    return false;
  }
  double mean = 0.0;
  for (int j = -kHalf; j <= kHalf; ++j)
    for (int i = -kHalf; i <= kHalf; ++i) mean += ref.at(u + i, v + j);
  mean /= kSize * kSize;
  double suu = 0.0, suv = 0.0, svv = 0.0;
  for (int j = -kHalf, k = 0; j <= kHalf; ++j) {
    for (int i = -kHalf; i <= kHalf; ++i, ++k) {
      ref_[k] = ref.at(u + i, v + j) - mean;
      gu_[k] = 0.5 * (ref.at(u + i + 1, v + j) - ref.at(u + i - 1, v + j));
      gv_[k] = 0.5 * (ref.at(u + i, v + j + 1) - ref.at(u + i, v + j - 1));
      suu += gu_[k] * gu_[k];
      suv += gu_[k] * gv_[k];
      svv += gv_[k] * gv_[k];
    }
  }
  const double det = suu * svv - suv * suv;
  // Both directions must carry gradient: the smaller eigenvalue of the
  // matrix, roughly det / trace, at least a few grey levels per pixel.
  if (!(det > 0.0) || det / (suu + svv) < 4.0 * kSize * kSize) return false;
  h_inv_[0] = svv / det;
  h_inv_[1] = -suv / det;
  h_inv_[2] = suu / det;
  return true;
}

bool PatchAligner::align(const Plane<std::uint8_t>& target, double u0, double v0, double max_shift, double* u,
                         double* v) const noexcept {
  double cu = u0, cv = v0;
  double patch[kSize * kSize];
  for (int it = 0; it < kIterations; ++it) {
    if (cu - kHalf < 0.0 || cv - kHalf < 0.0 || cu + kHalf + 1.0 >= target.width() ||
        cv + kHalf + 1.0 >= target.height()) {
      return false;
    }
    const double mean = sample_patch(target, cu, cv, patch);
    double bu = 0.0, bv = 0.0;
    for (int k = 0; k < kSize * kSize; ++k) {
      const double e = (patch[k] - mean) - ref_[k];
      bu += gu_[k] * e;
      bv += gv_[k] * e;
    }
    // The target patch at (cu, cv) looks like the reference moved by the
    // step: move back by it.
    const double du = h_inv_[0] * bu + h_inv_[1] * bv;
    const double dv = h_inv_[1] * bu + h_inv_[2] * bv;
    cu -= du;
    cv -= dv;
    if (!std::isfinite(cu) || !std::isfinite(cv) || std::abs(cu - u0) > max_shift || std::abs(cv - v0) > max_shift) {
      return false;
    }
    if (std::abs(du) < kConverged && std::abs(dv) < kConverged) break;
  }
  *u = cu;
  *v = cv;
  return true;
}

}  // namespace rtfuse::vision
