#pragma once
// Dense stereo disparity of a rectified grey pair by semi-global matching
// (Hirschmueller 2008) on census costs:
//
//   1. optionally halve both eyes (2x2 mean, FeatureFilters::halve);
//   2. 9x7 centre-symmetric census of each eye (census_transform.hpp) and the Hamming cost
//      of every pixel at every disparity (census_cost.hpp), kept as bytes;
//   3. aggregation along 8 (or 4) straight paths: along each path,
//      L(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d+-1) + P1,
//      min_k L(p-r, k) + P2) - min_k L(p-r, k), summed over the paths.
//      One pass down the image runs the paths that come from the left and
//      from above, one pass up the others; the sums of the first wait in a
//      16-bit volume. Path costs fit a byte (P2 <= 96), so sixteen
//      disparities go in a vector (simd_u8.hpp: SSE2, NEON or plain), or
//      thirty-two with AVX2 where the CPU has it (simd_avx2.hpp, chosen
//      at construction), the same integers;
//   4. per pixel, as the upward pass finishes its sums: winner-take-all,
//      uniqueness, parabola fraction, and per row the left-right check
//      (packed_winner.hpp; disparity_selection.hpp where the sums are too
//      wide to pack, with the same results); then speckles removed
//      (speckle_filter.hpp).
//
// Integer arithmetic from the pixels to the disparities, so every machine
// and every backend gives the same bits. All memory (the cost and sum
// volumes, the path rows, the census planes) is taken in the constructor
// for the largest image and disparity count; compute() allocates nothing,
// has no threads, no I/O and no clock. One matcher per thread.
#include <cstdint>
#include <memory>

#include "vision/disparity_image.hpp"
#include "vision/disparity_params.hpp"
#include "vision/plane.hpp"
#include "vision/speckle_filter.hpp"

namespace rtfuse::vision {

enum class DisparityStatus : std::uint8_t {
  kOk = 0,
  kNotConstructed,    // the matcher's parameters were refused (error())
  kBadImage,          // null data, a size <= 0 or a stride shorter than a row
  kSizeMismatch,      // left, right and the output differ in size
  kLargerThanWorkspace,  // the image exceeds the size given at construction
  kRangeTooWide,      // the disparity range is not narrower than the image
};

const char* to_string(DisparityStatus s) noexcept;

// The instructions the matcher's loops run on. Integer lanes have one
// right answer, so every backend gives the same disparities, bit for bit.
enum class DisparityBackend : std::uint8_t {
  kAuto,      // kAvx2 where it applies, else kBaseline
  kBaseline,  // the build's baseline vectors: SSE2 on x86-64, NEON on aarch64 (plain lanes if neither)
  kAvx2,      // 32-byte lanes, for x86-64 CPUs with AVX2 and matched disparities a multiple of 32;
              // elsewhere kBaseline is used
  kPlain,     // plain C++ lanes, the definition the others are tested against
};

const char* to_string(DisparityBackend b) noexcept;

class SemiGlobalMatcher {
 public:
  // For input images of at most max_width x max_height pixels. Check
  // valid(): sizes <= 0, a bad downscale, path count, disparity count (not
  // a multiple of 8 * downscale, or not narrower than max_width) or penalty
  // are refused with error() saying which and what would do. backend: see
  // DisparityBackend; the default takes the fastest this CPU runs.
  SemiGlobalMatcher(int max_width, int max_height, const DisparityParams& params = {},
                    DisparityBackend backend = DisparityBackend::kAuto);
  ~SemiGlobalMatcher();
  SemiGlobalMatcher(const SemiGlobalMatcher&) = delete;
  SemiGlobalMatcher& operator=(const SemiGlobalMatcher&) = delete;

  bool valid() const noexcept { return error_ == nullptr; }
  const char* error() const noexcept { return error_; }
  const DisparityParams& params() const noexcept { return params_; }
  // The backend compute() runs on (never kAuto once valid()).
  DisparityBackend backend() const noexcept { return backend_; }

  // The output's size for an input of width x height: the input's divided
  // by the downscale (an odd last column or row dropped).
  int output_width(int input_width) const noexcept { return input_width / params_.downscale; }
  int output_height(int input_height) const noexcept { return input_height / params_.downscale; }

  // The left eye's disparity (disparity_image.hpp) into out, which must be
  // output_width x output_height. Nothing is written unless kOk.
  DisparityStatus compute(const GreyView& left, const GreyView& right, const DisparityImage& out) noexcept;

  // Valid pixels of the last kOk compute().
  int valid_pixels() const noexcept { return valid_pixels_; }

 private:
  struct Workspace;
  void match(const GreyView& left, const GreyView& right, const DisparityImage& out) noexcept;

  DisparityParams params_;
  const char* error_ = nullptr;
  int max_width_ = 0, max_height_ = 0;  // matched (downscaled) pixels
  int disparities_ = 0;                 // matched pixels
  DisparityBackend backend_ = DisparityBackend::kAuto;
  std::unique_ptr<Workspace> ws_;
  int valid_pixels_ = 0;
};

}  // namespace rtfuse::vision
