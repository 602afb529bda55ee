#include "vision/feature_filters.hpp"

#include <algorithm>
#include <cstring>

namespace rtfuse::vision {
namespace {

// (g >> 7) + 128 for |g| <= 12240, the shift rounding towards minus
// infinity: what GCC and Clang do for a negative int (and C++20 requires).
static_assert((-1 >> 1) == -1, "the gradient bytes need an arithmetic right shift");
inline std::uint8_t gradient_byte(int g) noexcept { return static_cast<std::uint8_t>((g >> 7) + 128); }

template <class T>
void fill_border(Plane<T>& p, int width, int height, T value) noexcept {
  for (int v = 0; v < height; ++v) {
    T* r = p.row(v);
    if (v < 2 || v >= height - 2) {
      std::fill(r, r + width, value);
    } else {
      for (int u = 0; u < std::min(2, width); ++u) r[u] = value;
      for (int u = std::max(0, width - 2); u < width; ++u) r[u] = value;
    }
  }
}

// Calls row(v, r0..r4) for every row v with a whole 5 x 5 window (r0 two
// rows above v, r4 two below); nothing for an image narrower or lower than 5.
template <class Row>
void for_each_window_row(const GreyView& src, int w, Row&& row) noexcept {
  if (w < 5 || src.height < 5) return;
  for (int v = 2; v < src.height - 2; ++v) {
    row(v, src.row(v - 2), src.row(v - 1), src.row(v), src.row(v + 1), src.row(v + 2));
  }
}

}  // namespace

FeatureFilters::FeatureFilters(int max_width)
    : max_width_(max_width),
      smooth_(new std::int16_t[static_cast<std::size_t>(max_width)]()),
      diff_(new std::int16_t[static_cast<std::size_t>(max_width)]()),
      box3_(new std::int16_t[static_cast<std::size_t>(max_width)]()),
      box5_(new std::int16_t[static_cast<std::size_t>(max_width)]()),
      corner_(new std::int16_t[static_cast<std::size_t>(max_width)]()) {}

void FeatureFilters::halve(const GreyView& src, Plane<std::uint8_t>& dst) noexcept {
  const int w = src.width / 2, h = src.height / 2;
  for (int v = 0; v < h; ++v) {
    const std::uint8_t* a = src.row(2 * v);
    const std::uint8_t* b = src.row(2 * v + 1);
    std::uint8_t* out = dst.row(v);
    for (int u = 0; u < w; ++u) {
      const int sum = a[2 * u] + a[2 * u + 1] + b[2 * u] + b[2 * u + 1];
      out[u] = static_cast<std::uint8_t>(sum >> 2);  // non-negative: a plain shift
    }
  }
}

void FeatureFilters::sobel5x5(const GreyView& src, Plane<std::uint8_t>& du, Plane<std::uint8_t>& dv) noexcept {
  const int w = std::min(src.width, max_width_), h = src.height;
  fill_border(du, w, h, std::uint8_t{128});
  fill_border(dv, w, h, std::uint8_t{128});
  std::int16_t* s = smooth_.get();
  std::int16_t* d = diff_.get();
  for_each_window_row(src, w, [&](int v, const std::uint8_t* r0, const std::uint8_t* r1, const std::uint8_t* r2,
                                  const std::uint8_t* r3, const std::uint8_t* r4) {
    // Vertically: [1 4 6 4 1] for du, [-1 -2 0 2 1] for dv.
    for (int u = 0; u < w; ++u) {
      s[u] = static_cast<std::int16_t>(r0[u] + 4 * r1[u] + 6 * r2[u] + 4 * r3[u] + r4[u]);
      d[u] = static_cast<std::int16_t>(-r0[u] - 2 * r1[u] + 2 * r3[u] + r4[u]);
    }
    std::uint8_t* ou = du.row(v);
    std::uint8_t* ov = dv.row(v);
    // Horizontally: [-1 -2 0 2 1] for du, [1 4 6 4 1] for dv.
    for (int u = 2; u < w - 2; ++u) {
      ou[u] = gradient_byte(-s[u - 2] - 2 * s[u - 1] + 2 * s[u + 1] + s[u + 2]);
      ov[u] = gradient_byte(d[u - 2] + 4 * d[u - 1] + 6 * d[u] + 4 * d[u + 1] + d[u + 2]);
    }
  });
}

void FeatureFilters::sobel5x5_window(const GreyView& src, int u0, int v0, Plane<std::uint8_t>& du,
                                     Plane<std::uint8_t>& dv) noexcept {
  // Windows are small (refinement's 15 x 15): the vertical sums of one
  // output row live on the stack, 4 columns wider than the window.
  constexpr int kMaxWindow = 60;
  const int w = std::min(du.width(), kMaxWindow), h = du.height();
  std::int16_t s[kMaxWindow + 4], d[kMaxWindow + 4];
  for (int y = 0; y < h; ++y) {
    const int v = v0 + y;
    const std::uint8_t* r0 = src.row(v - 2) + u0 - 2;
    const std::uint8_t* r1 = src.row(v - 1) + u0 - 2;
    const std::uint8_t* r2 = src.row(v) + u0 - 2;
    const std::uint8_t* r3 = src.row(v + 1) + u0 - 2;
    const std::uint8_t* r4 = src.row(v + 2) + u0 - 2;
    for (int x = 0; x < w + 4; ++x) {
      s[x] = static_cast<std::int16_t>(r0[x] + 4 * r1[x] + 6 * r2[x] + 4 * r3[x] + r4[x]);
      d[x] = static_cast<std::int16_t>(-r0[x] - 2 * r1[x] + 2 * r3[x] + r4[x]);
    }
    std::uint8_t* ou = du.row(y);
    std::uint8_t* ov = dv.row(y);
    for (int x = 0; x < w; ++x) {
      ou[x] = gradient_byte(-s[x] - 2 * s[x + 1] + 2 * s[x + 3] + s[x + 4]);
      ov[x] = gradient_byte(d[x] + 4 * d[x + 1] + 6 * d[x + 2] + 4 * d[x + 3] + d[x + 4]);
    }
  }
}

void FeatureFilters::blob_corner5x5(const GreyView& src, Plane<std::int16_t>& blob,
                                    Plane<std::int16_t>& corner) noexcept {
  const int w = std::min(src.width, max_width_), h = src.height;
  fill_border(blob, w, h, std::int16_t{0});
  fill_border(corner, w, h, std::int16_t{0});
  std::int16_t* b3 = box3_.get();
  std::int16_t* b5 = box5_.get();
  std::int16_t* c = corner_.get();
  for_each_window_row(src, w, [&](int v, const std::uint8_t* r0, const std::uint8_t* r1, const std::uint8_t* r2,
                                  const std::uint8_t* r3, const std::uint8_t* r4) {
    for (int u = 0; u < w; ++u) {
      b3[u] = static_cast<std::int16_t>(r1[u] + r2[u] + r3[u]);
      b5[u] = static_cast<std::int16_t>(b3[u] + r0[u] + r4[u]);
      c[u] = static_cast<std::int16_t>(-r0[u] - r1[u] + r3[u] + r4[u]);  // rows [-1 -1 0 1 1]
    }
    const std::uint8_t* centre = r2;
    std::int16_t* ob = blob.row(v);
    std::int16_t* oc = corner.row(v);
    for (int u = 2; u < w - 2; ++u) {
      const int box3 = b3[u - 1] + b3[u] + b3[u + 1];
      const int box5 = b5[u - 2] + b5[u - 1] + b5[u] + b5[u + 1] + b5[u + 2];
      ob[u] = static_cast<std::int16_t>(2 * box3 - box5 + 7 * centre[u]);
      oc[u] = static_cast<std::int16_t>(c[u - 2] + c[u - 1] - c[u + 1] - c[u + 2]);  // columns [1 1 0 -1 -1]
    }
  });
}

}  // namespace rtfuse::vision
