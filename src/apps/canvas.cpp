#include "apps/canvas.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "apps/bitmap_font.hpp"
#include "apps/rgb_png.hpp"

namespace rtfuse::apps {
namespace {

// Cohen-Sutherland: cuts the segment a-b to the box [x0, x1] x [y0, y1];
// false when nothing of it is inside (or an end is not finite). Each cut
// puts one coordinate exactly on an edge and interpolates the other by a
// fraction in [0, 1], so ends at 1e300 clip as exactly as ends nearby.
bool clip_segment(double x0, double y0, double x1, double y1, PointPx* a, PointPx* b) noexcept {
  if (!std::isfinite(a->x) || !std::isfinite(a->y) || !std::isfinite(b->x) || !std::isfinite(b->y)) return false;
  enum : unsigned { kLeft = 1, kRight = 2, kTop = 4, kBottom = 8 };
  auto code = [&](const PointPx& p) {
    return (p.x < x0 ? kLeft : 0u) | (p.x > x1 ? kRight : 0u) | (p.y < y0 ? kTop : 0u) | (p.y > y1 ? kBottom : 0u);
  };
  unsigned ca = code(*a), cb = code(*b);
  for (int i = 0; i < 8; ++i) {  // each cut clears a bit for good: four per end at most
    if ((ca | cb) == 0) return true;
    if ((ca & cb) != 0) return false;  // both beyond the same edge
    PointPx* p = ca != 0 ? a : b;
    const PointPx& q = ca != 0 ? *b : *a;
    const unsigned c = ca != 0 ? ca : cb;
    // The other end is not beyond this edge, so the difference is not zero.
    if (c & (kLeft | kRight)) {
      const double edge = (c & kLeft) ? x0 : x1;
      p->y = p->y + (q.y - p->y) * ((edge - p->x) / (q.x - p->x));
      p->x = edge;
    } else {
      const double edge = (c & kTop) ? y0 : y1;
      p->x = p->x + (q.x - p->x) * ((edge - p->y) / (q.y - p->y));
      p->y = edge;
    }
    if (!std::isfinite(p->x) || !std::isfinite(p->y)) return false;
    (ca != 0 ? ca : cb) = code(*p);
  }
  return (ca | cb) == 0;
}

int px(double v) noexcept { return static_cast<int>(std::lround(v)); }

}  // namespace

Rect intersect(const Rect& a, const Rect& b) noexcept {
  const int x0 = std::max(a.x, b.x), y0 = std::max(a.y, b.y);
  const int x1 = std::min(a.right(), b.right()), y1 = std::min(a.bottom(), b.bottom());
  return Rect{x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0)};
}

Canvas::Canvas(int width, int height, Rgb background)
    : width_(std::max(1, width)),
      height_(std::max(1, height)),
      clip_{0, 0, width_, height_},
      background_(background),
      rgb_(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3u) {
  for (std::size_t i = 0; i < rgb_.size(); i += 3) {
    rgb_[i] = background.r;
    rgb_[i + 1] = background.g;
    rgb_[i + 2] = background.b;
  }
}

Rgb Canvas::at(int x, int y) const noexcept {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return background_;
  const std::uint8_t* p = &rgb_[index(x, y)];
  return Rgb{p[0], p[1], p[2]};
}

const std::uint8_t* Canvas::row(int y) const noexcept {
  return &rgb_[index(0, y)];
}

void Canvas::set_clip(const Rect& r) noexcept { clip_ = intersect(r, Rect{0, 0, width_, height_}); }

void Canvas::reset_clip() noexcept { clip_ = Rect{0, 0, width_, height_}; }

void Canvas::put(int x, int y, Rgb c) noexcept {
  if (!clip_.contains(x, y)) return;
  std::uint8_t* p = &rgb_[index(x, y)];
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

void Canvas::fill_rect(const Rect& r, Rgb c) noexcept {
  const Rect in = intersect(r, clip_);
  for (int y = in.y; y < in.bottom(); ++y)
    for (int x = in.x; x < in.right(); ++x) put(x, y, c);
}

void Canvas::stroke_rect(const Rect& r, Rgb c, int thickness) noexcept {
  if (r.empty()) return;
  const int t = std::max(1, std::min({thickness, (r.w + 1) / 2, (r.h + 1) / 2}));
  fill_rect(Rect{r.x, r.y, r.w, t}, c);
  fill_rect(Rect{r.x, r.bottom() - t, r.w, t}, c);
  fill_rect(Rect{r.x, r.y, t, r.h}, c);
  fill_rect(Rect{r.right() - t, r.y, t, r.h}, c);
}

void Canvas::pen(int x, int y, int thickness, Rgb c) noexcept {
  const int lo = -(thickness - 1) / 2;
  for (int dy = lo; dy < lo + thickness; ++dy)
    for (int dx = lo; dx < lo + thickness; ++dx) put(x + dx, y + dy, c);
}

void Canvas::line(PointPx a, PointPx b, Rgb c, int thickness) noexcept {
  const int t = std::max(1, thickness);
  // The pen reaches t pixels past a point: cut to the clip widened by that.
  if (!clip_segment(clip_.x - t, clip_.y - t, clip_.right() + t, clip_.bottom() + t, &a, &b)) return;
  const double dx = b.x - a.x, dy = b.y - a.y;
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(dx), std::abs(dy))));
  if (steps == 0) {
    pen(px(a.x), px(a.y), t, c);
    return;
  }
  for (int s = 0; s <= steps; ++s) {
    const double f = static_cast<double>(s) / steps;
    pen(px(a.x + f * dx), px(a.y + f * dy), t, c);
  }
}

void Canvas::dashed_line(PointPx a, PointPx b, Rgb c, int thickness, int dash, int gap) noexcept {
  const int t = std::max(1, thickness);
  if (!clip_segment(clip_.x - t, clip_.y - t, clip_.right() + t, clip_.bottom() + t, &a, &b)) return;
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  if (length == 0.0) {
    line(a, b, c, t);
    return;
  }
  const double on = std::max(1, dash), period = on + std::max(0, gap);
  const double ux = (b.x - a.x) / length, uy = (b.y - a.y) / length;
  for (double s = 0.0; s < length; s += period) {
    const double e = std::min(s + on, length);
    line(PointPx{a.x + s * ux, a.y + s * uy}, PointPx{a.x + e * ux, a.y + e * uy}, c, t);
  }
}

void Canvas::polyline(const std::vector<PointPx>& points, Rgb c, int thickness) noexcept {
  if (points.size() == 1) line(points[0], points[0], c, thickness);
  for (std::size_t i = 1; i < points.size(); ++i) line(points[i - 1], points[i], c, thickness);
}

void Canvas::marker(PointPx p, Marker kind, int radius, Rgb c, int thickness) noexcept {
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) return;
  // Far outside: nothing to draw, and the integer centre below stays in range.
  if (p.x < clip_.x - radius - 1 || p.x > clip_.right() + radius + 1 || p.y < clip_.y - radius - 1 ||
      p.y > clip_.bottom() + radius + 1)
    return;
  const int cx = px(p.x), cy = px(p.y), r = std::max(1, radius), t = std::max(1, thickness);
  switch (kind) {
    case Marker::kCircle:
    case Marker::kDisc: {
      // A ring of width t inside radius r + 0.5, or the whole disc.
      const double outer = r + 0.5, inner = kind == Marker::kDisc ? -1.0 : r + 0.5 - t;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const double d = std::hypot(dx, dy);
          if (d <= outer && d > inner) put(cx + dx, cy + dy, c);
        }
      break;
    }
    case Marker::kCross:
      line(PointPx{p.x - r, p.y - r}, PointPx{p.x + r, p.y + r}, c, t);
      line(PointPx{p.x - r, p.y + r}, PointPx{p.x + r, p.y - r}, c, t);
      break;
    case Marker::kPlus:
      line(PointPx{p.x - r, p.y}, PointPx{p.x + r, p.y}, c, t);
      line(PointPx{p.x, p.y - r}, PointPx{p.x, p.y + r}, c, t);
      break;
    case Marker::kSquare:
      stroke_rect(Rect{cx - r, cy - r, 2 * r + 1, 2 * r + 1}, c, t);
      break;
  }
}

int Canvas::text(int x, int y, std::string_view text, Rgb c, int scale, bool bold) noexcept {
  const int s = std::max(1, scale);
  for (std::size_t i = 0; i < text.size(); ++i) {
    const int gx = x + static_cast<int>(i) * kGlyphAdvance * s;
    if (gx >= clip_.right() || gx + kGlyphAdvance * s + 1 < clip_.x) continue;
    for (int row = 0; row < kGlyphHeight; ++row)
      for (int col = 0; col < kGlyphWidth; ++col) {
        if (!glyph_ink(text[i], col, row)) continue;
        fill_rect(Rect{gx + col * s, y + row * s, s + (bold ? 1 : 0), s}, c);
      }
  }
  return text_width(text, s);
}

namespace {

void copy_row(const void* context, int y, std::uint8_t* row) noexcept {
  const auto* canvas = static_cast<const Canvas*>(context);
  std::memcpy(row, canvas->row(y), static_cast<std::size_t>(canvas->width()) * 3u);
}

}  // namespace

bool write_png(const Canvas& canvas, const std::string& path, std::string* error) {
  return write_rgb_png(path, canvas.width(), canvas.height(), copy_row, &canvas, error);
}

}  // namespace rtfuse::apps
