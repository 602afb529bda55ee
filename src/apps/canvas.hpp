#pragma once
// An RGB raster to draw figures on: lines, rectangles, markers and text in
// the tools' bitmap font, every operation clipped to a rectangle (a plot's
// lines stop at its frame), written as a PNG. No anti-aliasing: each pixel
// is exactly one of the colours drawn, so tests can look for them. A tool's
// writer (allocates, does file I/O); never on the real-time path.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rtfuse::apps {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
constexpr bool operator==(Rgb a, Rgb b) noexcept { return a.r == b.r && a.g == b.g && a.b == b.b; }
constexpr bool operator!=(Rgb a, Rgb b) noexcept { return !(a == b); }

// Pixels [x, x + w) x [y, y + h); empty when w or h <= 0.
struct Rect {
  int x = 0, y = 0, w = 0, h = 0;
  int right() const noexcept { return x + w; }  // one past the last column
  int bottom() const noexcept { return y + h; }
  bool empty() const noexcept { return w <= 0 || h <= 0; }
  bool contains(int px, int py) const noexcept { return px >= x && px < right() && py >= y && py < bottom(); }
};
Rect intersect(const Rect& a, const Rect& b) noexcept;

// A position in pixels; pixel (i, j) covers [i - 0.5, i + 0.5) around its centre.
struct PointPx {
  double x = 0.0, y = 0.0;
};

enum class Marker { kCircle, kDisc, kCross, kPlus, kSquare };

class Canvas {
 public:
  // Sizes below 1 are taken as 1: a picture always has a pixel.
  Canvas(int width, int height, Rgb background);

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  // The colour at (x, y); the background colour outside the canvas.
  Rgb at(int x, int y) const noexcept;
  // Row y's 3 * width bytes (y within 0..height-1).
  const std::uint8_t* row(int y) const noexcept;

  // Later drawing only changes pixels inside r (cut to the canvas).
  void set_clip(const Rect& r) noexcept;
  void reset_clip() noexcept;
  const Rect& clip() const noexcept { return clip_; }

  void put(int x, int y, Rgb c) noexcept;
  void fill_rect(const Rect& r, Rgb c) noexcept;
  // A frame of `thickness` pixels inside r.
  void stroke_rect(const Rect& r, Rgb c, int thickness = 1) noexcept;
  // From a to b, `thickness` pixels wide (a square pen). A segment with a
  // non-finite end draws nothing; one far outside is cut to the clip first,
  // so its cost is bounded by the canvas, not by the coordinates.
  void line(PointPx a, PointPx b, Rgb c, int thickness = 1) noexcept;
  // As line, in dashes of `dash` pixels with `gap` pixels between them.
  void dashed_line(PointPx a, PointPx b, Rgb c, int thickness, int dash, int gap) noexcept;
  // Consecutive points joined; a non-finite point breaks the line there.
  void polyline(const std::vector<PointPx>& points, Rgb c, int thickness = 1) noexcept;
  // A marker centred on p, `radius` pixels from its centre to its edge.
  void marker(PointPx p, Marker kind, int radius, Rgb c, int thickness = 1) noexcept;
  // One line of text whose cell's top-left corner is (x, y) (see
  // bitmap_font.hpp); bold doubles every stroke one pixel to the right.
  // Returns text_width(text, scale).
  int text(int x, int y, std::string_view text, Rgb c, int scale = 1, bool bold = false) noexcept;

 private:
  void pen(int x, int y, int thickness, Rgb c) noexcept;
  std::size_t index(int x, int y) const noexcept {
    return (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) * 3u;
  }

  int width_;
  int height_;
  Rect clip_;
  Rgb background_;
  std::vector<std::uint8_t> rgb_;
};

// The canvas as an 8-bit RGB PNG; false and *error naming the path and the
// cause (errno text, or libpng's) as write_rgb_png.
bool write_png(const Canvas& canvas, const std::string& path, std::string* error);

}  // namespace rtfuse::apps
