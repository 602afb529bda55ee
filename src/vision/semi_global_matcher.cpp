#include "vision/semi_global_matcher.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <utility>

#include "vision/census_cost.hpp"
#include "vision/census_transform.hpp"
#include "vision/disparity_image.hpp"
#include "vision/disparity_selection.hpp"
#include "vision/feature_filters.hpp"
#include "vision/packed_winner.hpp"
#include "vision/simd_avx2.hpp"
#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {

// Path costs are bytes: along a path L(p, d) - min_k L(p-r, k) is at most
// P2, and min_k L(p, k) at most the largest matching cost (31), so with
// P2 <= kMaxP2 every path cost is at most 127: two paths add up in a byte
// before they are widened into the 16-bit sums, and 255 can mark "beyond
// the disparity range" (a step there never wins; adding P1 saturates).
constexpr std::uint8_t kPathBeyondRange = 0xff;
constexpr int kMaxP2 = 127 - kCensusBits;
// Each path row slot: [0] the slot's least cost, [31] and [32 + D] the
// beyond-range values, [32, 32 + D) the costs, aligned for 32-byte
// vectors; the row path's 32-lane load past the range reads up to
// [63 + D].
constexpr int kSlotPad = 64;
constexpr int kSlotFirst = 32;
// A cost volume larger than this is refused rather than allocated (3 GB of
// costs and sums).
constexpr long long kMaxCells = 1LL << 30;
// The workspace's arrays start on a cache line: with d a multiple of the
// lane count, the volumes' and path rows' vectors then never straddle one
// (32-byte vectors from malloc's 16-byte alignment would, every other).
constexpr std::size_t kAlign = 64;

// The matcher's loops, compiled once for the build's baseline (SSE2,
// NEON, or plain where neither; both NativeU8 and PlainU8 instantiate
// them) and once for AVX2 (simd_avx2.hpp), from the same source.
namespace lanes {
#include "vision/census_cost_kernels.hpp"
#include "vision/semi_global_kernels.hpp"
}  // namespace lanes
#if RTFUSE_SIMD_AVX2
RTFUSE_AVX2_BEGIN
namespace avx2 {
#include "vision/census_cost_kernels.hpp"
#include "vision/semi_global_kernels.hpp"
}  // namespace avx2
RTFUSE_AVX2_END
#endif

template <class T>
struct AlignedDelete {
  void operator()(T* p) const noexcept { ::operator delete[](p, std::align_val_t{kAlign}); }
};
template <class T>
using AlignedArray = std::unique_ptr<T[], AlignedDelete<T>>;

// n values of T on a cache line, zeroed if asked (the volumes are not:
// their pages are touched when first written).
template <class T>
AlignedArray<T> aligned_array(std::size_t n, bool zeroed = true) {
  T* p = static_cast<T*>(::operator new[](n * sizeof(T), std::align_val_t{kAlign}));
  if (zeroed) std::memset(p, 0, n * sizeof(T));
  return AlignedArray<T>(p);
}

// The backend a matcher with d matched disparities runs on.
DisparityBackend resolve_backend(DisparityBackend requested, int d) noexcept {
  if (requested == DisparityBackend::kPlain) return DisparityBackend::kPlain;
#if RTFUSE_SIMD_AVX2
  if (requested != DisparityBackend::kBaseline && d % simd::Avx2U8::kLanes == 0 && simd::cpu_has_avx2()) {
    return DisparityBackend::kAvx2;
  }
#else
  (void)d;
#endif
  return DisparityBackend::kBaseline;
}

}  // namespace

const char* to_string(DisparityStatus s) noexcept {
  switch (s) {
    case DisparityStatus::kOk:
      return "ok";
    case DisparityStatus::kNotConstructed:
      return "the matcher's parameters were refused at construction";
    case DisparityStatus::kBadImage:
      return "an image or the output is empty, null or has a stride shorter than its row";
    case DisparityStatus::kSizeMismatch:
      return "left, right and output sizes do not agree";
    case DisparityStatus::kLargerThanWorkspace:
      return "the image is larger than the matcher was constructed for";
    case DisparityStatus::kRangeTooWide:
      return "the disparity range is not narrower than the (downscaled) image";
  }
  return "unknown";
}

const char* to_string(DisparityBackend b) noexcept {
  switch (b) {
    case DisparityBackend::kAuto:
      return "auto";
    case DisparityBackend::kBaseline:
      return "baseline";
    case DisparityBackend::kAvx2:
      return "avx2";
    case DisparityBackend::kPlain:
      return "plain";
  }
  return "unknown";
}

struct SemiGlobalMatcher::Workspace {
  Workspace(int w, int h, int d, bool halve)
      : slot(d + kSlotPad),
        cost(aligned_array<std::uint8_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) *
                                             static_cast<std::size_t>(d) +
                                             kSlotPad,
                                         false)),
        sums(aligned_array<std::int16_t>(
            static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(d), false)),
        reversed_stride(w + d + 32),
        right_reversed(
            aligned_array<std::uint8_t>(static_cast<std::size_t>(kCensusPlanes) * static_cast<std::size_t>(reversed_stride))),
        path_rows(aligned_array<std::uint8_t>(static_cast<std::size_t>(6 * w + 3) * static_cast<std::size_t>(slot), false)),
        disparity(w, h),
        left_best(aligned_array<std::int16_t>(static_cast<std::size_t>(w))),
        right_best(aligned_array<std::int16_t>(static_cast<std::size_t>(w + d))),
        right_cost(aligned_array<std::int16_t>(static_cast<std::size_t>(w + d))),
        total(aligned_array<std::int16_t>(static_cast<std::size_t>(d))),
        row_sums(aligned_array<std::int16_t>(static_cast<std::size_t>(w) * static_cast<std::size_t>(d))),
        speckles(w * h) {
    if (halve) {
      half_left = Plane<std::uint8_t>(w, h);
      half_right = Plane<std::uint8_t>(w, h);
    }
    for (int g = 0; g < kCensusPlanes; ++g) {
      census_left[g] = Plane<std::uint8_t>(w, h);
      census_right[g] = Plane<std::uint8_t>(w, h);
    }
    // Every slot: zero costs between beyond-range guards; the guards are
    // never written again.
    const std::size_t slots = static_cast<std::size_t>(6 * w + 3);
    for (std::size_t i = 0; i < slots; ++i) {
      std::uint8_t* s = path_rows.get() + i * static_cast<std::size_t>(slot);
      std::fill(s, s + slot, std::uint8_t{0});
      s[kSlotFirst - 1] = kPathBeyondRange;
      s[kSlotFirst + d] = kPathBeyondRange;
    }
    for (int r = 0; r < 6; ++r) rows[r] = path_rows.get() + static_cast<std::size_t>(r * w) * static_cast<std::size_t>(slot);
    horizontal[0] = path_rows.get() + static_cast<std::size_t>(6 * w) * static_cast<std::size_t>(slot);
    horizontal[1] = horizontal[0] + slot;
    zero = horizontal[1] + slot;
  }

  int slot;
  AlignedArray<std::uint8_t> cost;  // [y][x][d]
  AlignedArray<std::int16_t> sums;  // [y][x][d]
  int reversed_stride;
  AlignedArray<std::uint8_t> right_reversed;  // per census plane, one row reversed
  AlignedArray<std::uint8_t> path_rows;
  std::uint8_t* rows[6] = {};        // three directions' previous and current rows
  std::uint8_t* horizontal[2] = {};  // the row path's previous and current pixel
  std::uint8_t* zero = nullptr;      // where a path enters the image
  Plane<std::uint8_t> half_left, half_right;
  Plane<std::uint8_t> census_left[kCensusPlanes], census_right[kCensusPlanes];
  Plane<std::int16_t> disparity;  // matched pixels * kDisparityScale, -1 invalid
  AlignedArray<std::int16_t> left_best, right_best;
  AlignedArray<std::int16_t> right_cost;
  AlignedArray<std::int16_t> total;     // one pixel's complete sums (fused selection)
  AlignedArray<std::int16_t> row_sums;  // one row's (two-pass selection)
  SpeckleFilter speckles;
};

SemiGlobalMatcher::SemiGlobalMatcher(int max_width, int max_height, const DisparityParams& params,
                                     DisparityBackend backend)
    : params_(params) {
  const DisparityParams& p = params;
  if (max_width <= 0 || max_height <= 0) {
    error_ = "the largest image size must be positive";
  } else if (p.downscale != 1 && p.downscale != 2) {
    error_ = "downscale must be 1 (full resolution) or 2 (half)";
  } else if (p.paths != 4 && p.paths != 8) {
    error_ = "paths must be 4 or 8";
  } else if (p.disparities <= 0 || p.disparities > 1024 || p.disparities % (16 * p.downscale) != 0) {
    error_ = p.downscale == 1 ? "disparities must be a multiple of 16 in 16..1024"
                              : "disparities must be a multiple of 32 in 32..1024 with downscale 2";
  } else if (p.disparities / p.downscale >= max_width / p.downscale) {
    error_ = "the disparity range must be narrower than the image: fewer disparities or a wider image";
  } else if (p.p1 < 0 || p.p2 < p.p1 || p.p2 > kMaxP2) {
    error_ = "penalties must satisfy 0 <= p1 <= p2 <= 96 (the census cost's scale is 0..31)";
  } else if (p.uniqueness_percent < 0 || p.uniqueness_percent > 99) {
    error_ = "uniqueness_percent must be in 0..99";
  } else if (p.speckle_window < 0 || p.speckle_range < 0) {
    error_ = "speckle_window and speckle_range must not be negative";
  }
  if (error_ != nullptr) return;
  max_width_ = max_width / p.downscale;
  max_height_ = max_height / p.downscale;
  disparities_ = p.disparities / p.downscale;
  if (static_cast<long long>(max_width_) * max_height_ * disparities_ > kMaxCells) {
    error_ = "the image size times the disparities is too large a cost volume (over 2^30 cells): downscale";
    return;
  }
  ws_ = std::make_unique<Workspace>(max_width_, max_height_, disparities_, p.downscale == 2);
  backend_ = resolve_backend(backend, disparities_);
}

SemiGlobalMatcher::~SemiGlobalMatcher() = default;

DisparityStatus SemiGlobalMatcher::compute(const GreyView& left, const GreyView& right,
                                           const DisparityImage& out) noexcept {
  if (!valid()) return DisparityStatus::kNotConstructed;
  if (!left.valid() || !right.valid() || !out.valid()) return DisparityStatus::kBadImage;
  if (left.width != right.width || left.height != right.height || out.width != output_width(left.width) ||
      out.height != output_height(left.height)) {
    return DisparityStatus::kSizeMismatch;
  }
  const int w = output_width(left.width), h = output_height(left.height);
  if (w > max_width_ || h > max_height_) return DisparityStatus::kLargerThanWorkspace;
  if (disparities_ >= w) return DisparityStatus::kRangeTooWide;
  match(left, right, out);
  return DisparityStatus::kOk;
}

void SemiGlobalMatcher::match(const GreyView& left_in, const GreyView& right_in, const DisparityImage& out) noexcept {
  Workspace& ws = *ws_;
  const int w = output_width(left_in.width), h = output_height(left_in.height), d = disparities_;
  GreyView left = left_in, right = right_in;
  if (params_.downscale == 2) {
    FeatureFilters::halve(left_in, ws.half_left);
    FeatureFilters::halve(right_in, ws.half_right);
    left = GreyView{ws.half_left.row(0), w, h, ws.half_left.stride()};
    right = GreyView{ws.half_right.row(0), w, h, ws.half_right.stride()};
  }
  // Sums are at most paths * (P2 + the largest cost): see kMaxP2.
  const bool fused = packed_winner_fits(params_.paths * (params_.p2 + kCensusBits), d);
  // The census itself (a twentieth of the time) stays on the baseline's
  // lanes with AVX2; the plain backend is plain throughout.
  if (backend_ == DisparityBackend::kPlain) {
    census_transform_9x7_portable(left, ws.census_left);
    census_transform_9x7_portable(right, ws.census_right);
  } else {
    census_transform_9x7(left, ws.census_left);
    census_transform_9x7(right, ws.census_right);
  }
  switch (backend_) {
    case DisparityBackend::kPlain:
      lanes::aggregate_image<simd::PlainU8>(ws, params_, w, h, d, fused);
      break;
#if RTFUSE_SIMD_AVX2
    case DisparityBackend::kAvx2:  // only where cpu_has_avx2() (resolve_backend)
      avx2::aggregate_image<simd::Avx2U8>(ws, params_, w, h, d, fused);
      break;
#endif
    default:
      lanes::aggregate_image<simd::NativeU8>(ws, params_, w, h, d, fused);
      break;
  }

  // The census window's margin repeats border pixels: no estimate there.
  for (int y = 0; y < h; ++y) {
    std::int16_t* row = ws.disparity.row(y);
    if (y < kCensusHalfHeight || y >= h - kCensusHalfHeight) {
      std::fill(row, row + w, std::int16_t{-1});
      continue;
    }
    for (int x = 0; x < std::min(kCensusHalfWidth, w); ++x) row[x] = -1;
    for (int x = std::max(0, w - kCensusHalfWidth); x < w; ++x) row[x] = -1;
  }
  if (params_.speckle_window > 0) {
    ws.speckles.filter(ws.disparity.row(0), w, h, ws.disparity.stride(), params_.speckle_window,
                       params_.speckle_range * kDisparityScale);
  }
  int valid = 0;
  for (int y = 0; y < h; ++y) {
    const std::int16_t* src = ws.disparity.row(y);
    std::uint16_t* dst = out.row(y);
    for (int x = 0; x < w; ++x) {
      const int v = src[x];
      valid += v >= 0 ? 1 : 0;
      dst[x] = v >= 0 ? static_cast<std::uint16_t>(v * params_.downscale) : kInvalidDisparity;
    }
  }
  valid_pixels_ = valid;
}

void select_disparity_row_packed(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                 int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  lanes::select_row_packed<simd::NativeI16>(sums, width, disparities, uniqueness_percent, lr_max_diff, scratch, out);
}

void select_disparity_row_packed_portable(const std::int16_t* sums, int width, int disparities,
                                          int uniqueness_percent, int lr_max_diff, const DisparityRowScratch& scratch,
                                          std::int16_t* out) noexcept {
  lanes::select_row_packed<simd::PlainI16>(sums, width, disparities, uniqueness_percent, lr_max_diff, scratch, out);
}

bool select_disparity_row_packed_avx2(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                                      int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
#if RTFUSE_SIMD_AVX2
  if (!simd::cpu_has_avx2() || disparities % simd::Avx2I16::kLanes != 0) return false;
  avx2::select_row_packed<simd::Avx2I16>(sums, width, disparities, uniqueness_percent, lr_max_diff, scratch, out);
  return true;
#else
  (void)sums, (void)width, (void)disparities, (void)uniqueness_percent, (void)lr_max_diff, (void)scratch, (void)out;
  return false;
#endif
}

}  // namespace rtfuse::vision
