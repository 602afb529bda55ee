#include "drivers/camera/stereo_rectifier.hpp"

#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rtfuse::drivers {

namespace {

constexpr std::uint32_t kPairMask = 0x007F007Fu;  // two 7-bit weights as int16 lanes
constexpr int kMaxSide = 8192;
constexpr int kRoundingShift = 2 * StereoRectifier::kFractionBits;
constexpr std::int32_t kRounding = 1 << (kRoundingShift - 1);

inline std::uint32_t load_u32(const std::uint8_t* p) noexcept {
  std::uint32_t w;
  std::memcpy(&w, p, sizeof w);  // unaligned load, same on every architecture
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  w = __builtin_bswap32(w);  // byte 0 -> bits 0..7, byte 2 -> bits 16..23
#endif
  return w;
}

// Two luma samples (bytes 0 and 2 of Y0 U Y1 V) as 16-bit lanes.
inline std::uint32_t luma_pair(const std::uint8_t* p) noexcept { return load_u32(p) & 0x00FF00FFu; }

// One rectified pixel, plain C++. Both horizontal interpolations come from
// one 64-bit multiply:
//   L = a | b << 16 | c << 32 | d << 48   (top-left, top-right, bottom-left, bottom-right)
//   M = wx | (64 - wx) << 16
//   L * M holds a * (64 - wx) + b * wx in bits 16..31 and c * (64 - wx) +
//   d * wx in bits 48..63; every 16-bit lane stays below 255 * 64 < 2^16, so
//   no lane carries into the next (bits 64 and up are dropped).
// Then top * (64 - wy) + bottom * wy, rounded half up from 12 fraction bits:
// exactly what the SSE2 kernel computes with pmaddwd.
inline std::uint8_t interpolate(const std::uint8_t* base, std::size_t bpl, std::uint32_t offset,
                                std::uint32_t weights) noexcept {
  const std::uint8_t* p = base + offset;
  const std::uint64_t lanes =
      static_cast<std::uint64_t>(luma_pair(p)) | (static_cast<std::uint64_t>(luma_pair(p + bpl)) << 32);
  const std::uint32_t pair = weights & kPairMask;                // 64 - wx | wx << 16
  const std::uint32_t m = (pair >> 16) | (pair << 16);           // wx | (64 - wx) << 16
  const std::uint64_t h = lanes * m;
  const std::int32_t top = static_cast<std::int32_t>((h >> 16) & 0xFFFFu);
  const std::int32_t bottom = static_cast<std::int32_t>(h >> 48);
  const std::int32_t wy_rest = static_cast<std::int32_t>((weights >> 8) & 0x7Fu);  // 64 - wy
  const std::int32_t wy = static_cast<std::int32_t>(weights >> 24);
  return static_cast<std::uint8_t>((top * wy_rest + bottom * wy + kRounding) >> kRoundingShift);
}

template <typename Entry>
void row_portable(const Entry* e, int count, const std::uint8_t* base, std::size_t bpl, std::uint8_t* out) noexcept {
  for (int u = 0; u < count; ++u) out[u] = interpolate(base, bpl, e[u].offset, e[u].weights);
}

#if defined(__SSE2__)
// Four rectified pixels per step (SSE2 is part of every x86-64). The source
// reads stay scalar (a gather), the arithmetic is three pmaddwd:
//   horizontal: [a b] . [64 - wx, wx] and [c d] . [64 - wx, wx]
//   vertical:   [top bottom] . [64 - wy, wy]
// All products and sums are exact integers, so the bytes equal
// row_portable()'s.
template <typename Entry>
void row_sse2(const Entry* e, int count, const std::uint8_t* base, std::size_t bpl, std::uint8_t* out) noexcept {
  static_assert(sizeof(Entry) == 8, "offset, weights");
  const __m128i luma_mask = _mm_set1_epi32(0x00FF00FF);
  const __m128i pair_mask = _mm_set1_epi32(static_cast<int>(kPairMask));
  const __m128i rounding = _mm_set1_epi32(kRounding);
  int u = 0;
  for (; u + 4 <= count; u += 4) {
    const Entry* q = e + u;
    const std::uint8_t* p0 = base + q[0].offset;
    const std::uint8_t* p1 = base + q[1].offset;
    const std::uint8_t* p2 = base + q[2].offset;
    const std::uint8_t* p3 = base + q[3].offset;
    const __m128i top = _mm_and_si128(
        _mm_unpacklo_epi64(_mm_unpacklo_epi32(_mm_cvtsi32_si128(static_cast<int>(load_u32(p0))),
                                              _mm_cvtsi32_si128(static_cast<int>(load_u32(p1)))),
                           _mm_unpacklo_epi32(_mm_cvtsi32_si128(static_cast<int>(load_u32(p2))),
                                              _mm_cvtsi32_si128(static_cast<int>(load_u32(p3))))),
        luma_mask);
    const __m128i bottom = _mm_and_si128(
        _mm_unpacklo_epi64(_mm_unpacklo_epi32(_mm_cvtsi32_si128(static_cast<int>(load_u32(p0 + bpl))),
                                              _mm_cvtsi32_si128(static_cast<int>(load_u32(p1 + bpl)))),
                           _mm_unpacklo_epi32(_mm_cvtsi32_si128(static_cast<int>(load_u32(p2 + bpl))),
                                              _mm_cvtsi32_si128(static_cast<int>(load_u32(p3 + bpl))))),
        luma_mask);
    // The four entries' weight words: [o0 w0 o1 w1] [o2 w2 o3 w3] -> [w0 w1 w2 w3].
    const __m128i e01 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
    const __m128i e23 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 2));
    const __m128i weights = _mm_castps_si128(
        _mm_shuffle_ps(_mm_castsi128_ps(e01), _mm_castsi128_ps(e23), _MM_SHUFFLE(3, 1, 3, 1)));
    const __m128i wx = _mm_and_si128(weights, pair_mask);                     // 64 - wx, wx
    const __m128i wy = _mm_and_si128(_mm_srli_epi32(weights, 8), pair_mask);  // 64 - wy, wy
    const __m128i h_top = _mm_madd_epi16(top, wx);
    const __m128i h_bottom = _mm_madd_epi16(bottom, wx);
    const __m128i both = _mm_or_si128(h_top, _mm_slli_epi32(h_bottom, 16));  // < 2^14 each: int16 lanes
    const __m128i v = _mm_srli_epi32(_mm_add_epi32(_mm_madd_epi16(both, wy), rounding), kRoundingShift);
    const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(v, v), v);
    const int four = _mm_cvtsi128_si32(bytes);
    std::memcpy(out + u, &four, sizeof four);
  }
  row_portable(e + u, count - u, base, bpl, out + u);
}
#endif

}  // namespace

StereoRectifier::StereoRectifier(const StereoCalibration& calibration, const StereoRectification& rectification,
                                 int bytes_per_line)
    : width_(rectification.width), height_(rectification.height) {
  if (width_ < 2 || height_ < 2 || width_ > kMaxSide || height_ > kMaxSide) {
    width_ = height_ = 0;
    return;
  }
  bytes_per_line_ = bytes_per_line == 0 ? 4 * width_ : bytes_per_line;
  if (bytes_per_line_ < 4 * width_ || bytes_per_line_ > 4 * kMaxSide + 65536) {
    width_ = height_ = bytes_per_line_ = 0;
    return;
  }
  table_.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 2);
  const RawPositionMap maps[2] = {RawPositionMap(calibration.left, rectification.left),
                                  RawPositionMap(calibration.right, rectification.right)};
  const double max_qx = static_cast<double>(width_ - 1) * kOne;
  const double max_qy = static_cast<double>(height_ - 1) * kOne;
  const std::uint32_t bpl = static_cast<std::uint32_t>(bytes_per_line_);
  Entry* e = table_.data();
  for (int v = 0; v < height_; ++v) {
    for (int eye = 0; eye < 2; ++eye) {
      for (int u = 0; u < width_; ++u, ++e) {
        double x = 0.0, y = 0.0;
        bool inside = maps[eye].at(u, v, &x, &y);
        // Quantise to 1/64 px (floor is exact, so the same bits everywhere).
        const double qx = inside ? std::floor(x * kOne + 0.5) : -1.0;
        const double qy = inside ? std::floor(y * kOne + 0.5) : -1.0;
        inside = inside && qx >= 0.0 && qy >= 0.0 && qx <= max_qx && qy <= max_qy;
        if (!inside) {
          // Any valid pixel will do: zero weights make the result 0.
          *e = Entry{static_cast<std::uint32_t>(eye * width_ * 2), 0u};
          continue;
        }
        int x0 = static_cast<int>(qx) >> kFractionBits;
        int y0 = static_cast<int>(qy) >> kFractionBits;
        int wx = static_cast<int>(qx) & (kOne - 1);
        int wy = static_cast<int>(qy) & (kOne - 1);
        // On the last column / row: the same value from the pair before, so
        // the 2 x 2 neighbourhood never leaves the image.
        if (x0 == width_ - 1) {
          x0 -= 1;
          wx = kOne;
        }
        if (y0 == height_ - 1) {
          y0 -= 1;
          wy = kOne;
        }
        const std::uint32_t offset =
            static_cast<std::uint32_t>(y0) * bpl + static_cast<std::uint32_t>(eye * width_ + x0) * 2u;
        const std::uint32_t weights =
            static_cast<std::uint32_t>(kOne - wx) | (static_cast<std::uint32_t>(kOne - wy) << 8) |
            (static_cast<std::uint32_t>(wx) << 16) | (static_cast<std::uint32_t>(wy) << 24);
        *e = Entry{offset, weights};
      }
    }
  }
}

bool StereoRectifier::set_bytes_per_line(int bytes_per_line) noexcept {
  if (table_.empty() || bytes_per_line < 4 * width_ || bytes_per_line > 4 * kMaxSide + 65536) return false;
  const std::uint32_t old_bpl = static_cast<std::uint32_t>(bytes_per_line_);
  const std::uint32_t new_bpl = static_cast<std::uint32_t>(bytes_per_line);
  for (Entry& e : table_) e.offset = (e.offset / old_bpl) * new_bpl + e.offset % old_bpl;
  bytes_per_line_ = bytes_per_line;
  return true;
}

StereoRectifier::Sample StereoRectifier::sample(int eye, int u, int v) const noexcept {
  if (table_.empty() || eye < 0 || eye > 1 || u < 0 || u >= width_ || v < 0 || v >= height_) return {};
  const Entry& e = table_[(static_cast<std::size_t>(v) * 2 + static_cast<std::size_t>(eye)) *
                              static_cast<std::size_t>(width_) +
                          static_cast<std::size_t>(u)];
  const int bpl = bytes_per_line_;
  const int offset = static_cast<int>(e.offset);
  return {(offset % bpl) / 2 - eye * width_, offset / bpl, static_cast<int>((e.weights >> 16) & 0x7Fu),
          static_cast<int>(e.weights >> 24), e.weights != 0};
}

bool StereoRectifier::frame_fits(const YuyvFrameView& frame, GreyImageView left, GreyImageView right) const noexcept {
  if (table_.empty() || frame.data == nullptr || left.data == nullptr || right.data == nullptr) return false;
  if (frame.width != 2 * width_ || frame.height != height_ || frame.bytes_per_line != bytes_per_line_) return false;
  if (left.stride < width_ || right.stride < width_) return false;
  const std::size_t needed = static_cast<std::size_t>(bytes_per_line_) * static_cast<std::size_t>(height_ - 1) +
                             static_cast<std::size_t>(frame.width) * 2;
  return frame.size >= needed;
}

// Row by row, left eye then right eye: the table is read strictly in order
// and both eyes' reads fall on the same few source lines.
bool StereoRectifier::rectify(const YuyvFrameView& frame, GreyImageView left, GreyImageView right) const noexcept {
#if defined(__SSE2__)
  if (!frame_fits(frame, left, right)) return false;
  const std::size_t bpl = static_cast<std::size_t>(bytes_per_line_);
  const Entry* e = table_.data();
  const std::size_t w = static_cast<std::size_t>(width_);
  for (int v = 0; v < height_; ++v) {
    row_sse2(e, width_, frame.data, bpl, left.data + static_cast<std::size_t>(v) * static_cast<std::size_t>(left.stride));
    row_sse2(e + w, width_, frame.data, bpl,
             right.data + static_cast<std::size_t>(v) * static_cast<std::size_t>(right.stride));
    e += 2 * w;
  }
  return true;
#else
  return rectify_portable(frame, left, right);
#endif
}

bool StereoRectifier::rectify_portable(const YuyvFrameView& frame, GreyImageView left,
                                       GreyImageView right) const noexcept {
  if (!frame_fits(frame, left, right)) return false;
  const std::size_t bpl = static_cast<std::size_t>(bytes_per_line_);
  const Entry* e = table_.data();
  const std::size_t w = static_cast<std::size_t>(width_);
  for (int v = 0; v < height_; ++v) {
    row_portable(e, width_, frame.data, bpl,
                 left.data + static_cast<std::size_t>(v) * static_cast<std::size_t>(left.stride));
    row_portable(e + w, width_, frame.data, bpl,
                 right.data + static_cast<std::size_t>(v) * static_cast<std::size_t>(right.stride));
    e += 2 * w;
  }
  return true;
}

}  // namespace rtfuse::drivers
