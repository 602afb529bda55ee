#include "apps/stereo_png.hpp"

#include <png.h>

#include <cstddef>
#include <cstdio>
#include <cstring>
#include <vector>

#include "apps/bitmap_font.hpp"
#include "apps/canvas.hpp"
#include "apps/legend.hpp"
#include "apps/rgb_png.hpp"

namespace rtfuse::apps {
namespace {

constexpr int kHeaderLines = 5;
constexpr int kHeaderPad = 8;
constexpr Rgb kHeaderPaper{245, 245, 245};
constexpr Rgb kHeaderInk{0, 0, 0};
constexpr Rgb kHeaderRule{90, 90, 90};

// Text twice the font's size on a pair wide enough to hold a line of it
// (VGA and up), else the font's own size: the header reads at either.
int header_scale(int width) { return 2 * width >= 900 ? 2 : 1; }

std::string format(const char* fmt, double a, double b, double c, double d) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

// The band: what, when, the rectified camera, the guide lines' legend, and
// which half is which eye; a rule under it to set it off from the pair.
Canvas draw_header(const StereoPngHeader& h, int width, int height, int guide_every_px) {
  const int s = header_scale(width);
  Canvas band(2 * width, stereo_png_header_rows(width), kHeaderPaper);
  const int line = kLineSpacing * s;
  int y = kHeaderPad;
  band.text(kHeaderPad, y, "rectified stereo pair: " + h.source, kHeaderInk, s, true);
  y += line;
  const std::string size = std::to_string(width) + " x " + std::to_string(height) + " px per eye";
  band.text(kHeaderPad, y, h.when.empty() ? size : size + ", " + h.when, kHeaderInk, s);
  y += line;
  band.text(kHeaderPad, y,
            format("rectified fx %.2f px, cx %.2f px, cy %.2f px, baseline %.4f m", h.fx, h.cx, h.cy, h.baseline_m),
            kHeaderInk, s);
  y += line;
  const Rgb green{kGuideRgb[0], kGuideRgb[1], kGuideRgb[2]};
  const std::string guides = guide_every_px > 0
                                 ? "guide every " + std::to_string(guide_every_px) +
                                       " rows: a feature sits on the same line in both eyes"
                                 : "no guide lines (--guide 0)";
  draw_legend_row(band, kHeaderPad, y, {LegendEntry{guides, green, false, Marker::kDisc, 3, false}}, s);
  y += line;
  for (int eye = 0; eye < 2; ++eye) {
    const char* name = eye == 0 ? "left eye" : "right eye";
    band.text(eye * width + (width - text_width(name, s)) / 2, y, name, kHeaderInk, s, true);
  }
  band.fill_rect(Rect{0, band.height() - 2, band.width(), 2}, kHeaderRule);
  return band;
}

struct Picture {
  const std::uint8_t* left;
  const std::uint8_t* right;
  int width, height, stride, guide_every_px;
  const Canvas* header;  // null: no band
  int header_rows;
};

// One RGB row of the picture: the header band, the two eyes as grey, or a
// guide line.
void fill_row(const void* context, int y, std::uint8_t* row) noexcept {
  const Picture& p = *static_cast<const Picture*>(context);
  const int n = 2 * p.width;
  if (y < p.header_rows) {
    std::memcpy(row, p.header->row(y), static_cast<std::size_t>(n) * 3u);
    return;
  }
  y -= p.header_rows;
  if (p.guide_every_px > 0 && y > 0 && y % p.guide_every_px == 0) {
    for (int x = 0; x < n; ++x) std::memcpy(row + 3 * x, kGuideRgb, 3);
    return;
  }
  const std::ptrdiff_t offset = static_cast<std::ptrdiff_t>(y) * p.stride;
  for (int eye = 0; eye < 2; ++eye) {
    const std::uint8_t* src = (eye == 0 ? p.left : p.right) + offset;
    std::uint8_t* dst = row + 3 * eye * p.width;
    for (int x = 0; x < p.width; ++x) dst[3 * x] = dst[3 * x + 1] = dst[3 * x + 2] = src[x];
  }
}

bool fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

}  // namespace

int stereo_png_header_rows(int width) {
  const int s = header_scale(width);
  return 2 * kHeaderPad + (kHeaderLines - 1) * kLineSpacing * s + text_height(s) + 2;  // + the rule
}

bool write_stereo_png(const std::string& path, const std::uint8_t* left, const std::uint8_t* right, int width,
                      int height, int stride, int guide_every_px, std::string* error) {
  return write_stereo_png(path, left, right, width, height, stride, guide_every_px, nullptr, error);
}

bool write_stereo_png(const std::string& path, const std::uint8_t* left, const std::uint8_t* right, int width,
                      int height, int stride, int guide_every_px, const StereoPngHeader* header,
                      std::string* error) {
  const std::string what = "stereo PNG " + path + ": ";
  // Checked before opening, so bad arguments never truncate an existing file.
  if (left == nullptr || right == nullptr) return fail(error, what + "no image (null pixels)");
  if (width <= 0 || height <= 0)
    return fail(error, what + "size " + std::to_string(width) + "x" + std::to_string(height) + " must be positive");
  if (stride < width)
    return fail(error, what + "stride " + std::to_string(stride) + " is less than the width " + std::to_string(width));
  const int header_rows = header != nullptr ? stereo_png_header_rows(width) : 0;
  if (width > PNG_USER_WIDTH_MAX / 2 || height > PNG_USER_HEIGHT_MAX - header_rows)
    return fail(error, what + "pair " + std::to_string(width) + "x" + std::to_string(height) +
                           " exceeds libpng's limits (" + std::to_string(PNG_USER_WIDTH_MAX) + " px per side)");

  Canvas band(1, 1, kHeaderPaper);
  if (header != nullptr) band = draw_header(*header, width, height, guide_every_px);
  const Picture picture{left, right, width, height, stride, guide_every_px, &band, header_rows};
  return write_rgb_png(path, 2 * width, header_rows + height, fill_row, &picture, error);
}

}  // namespace rtfuse::apps
