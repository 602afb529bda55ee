#include "apps/legend.hpp"

#include <algorithm>

#include "apps/bitmap_font.hpp"

namespace rtfuse::apps {
namespace {

constexpr Rgb kBoxFill{255, 255, 255};
constexpr Rgb kBoxFrame{120, 120, 120};
constexpr Rgb kLabel{0, 0, 0};
constexpr int kPad = 8;       // box frame to content
constexpr int kSwatchGap = 8;  // swatch to label

int row_height(int scale) { return kLineSpacing * scale; }

// The swatch in the box [x, x + kSwatchPx) around the middle of a text
// line whose cell starts at y.
void draw_swatch(Canvas& canvas, int x, int y, const LegendEntry& e, int scale) {
  const double mid = y + kCapHeight * scale / 2.0;
  if (e.is_marker) {
    canvas.marker(PointPx{x + kSwatchPx / 2.0, mid}, e.marker, std::max(4, 3 * scale), e.colour, 2);
    return;
  }
  // Inset by the pen's half width: the swatch's ink stays within its space.
  const int t = std::max(3, e.thickness);
  const PointPx a{x + t / 2.0, mid}, b{x + kSwatchPx - 1.0 - t / 2.0, mid};
  if (e.dashed) {
    canvas.dashed_line(a, b, e.colour, t, 8, 4);
  } else {
    canvas.line(a, b, e.colour, t);
  }
}

int entry_width(const LegendEntry& e, int scale) { return kSwatchPx + kSwatchGap + text_width(e.label, scale); }

}  // namespace

Rect legend_box_size(const std::vector<LegendEntry>& entries, int scale) {
  int w = 0;
  for (const LegendEntry& e : entries) w = std::max(w, entry_width(e, scale));
  const int rows = static_cast<int>(entries.size());
  const int h = rows > 0 ? (rows - 1) * row_height(scale) + text_height(scale) : 0;
  return Rect{0, 0, w + 2 * kPad, h + 2 * kPad};
}

Rect draw_legend(Canvas& canvas, int x, int y, const std::vector<LegendEntry>& entries, int scale) {
  Rect box = legend_box_size(entries, scale);
  box.x = x;
  box.y = y;
  if (entries.empty()) return Rect{x, y, 0, 0};
  canvas.fill_rect(box, kBoxFill);
  canvas.stroke_rect(box, kBoxFrame);
  int row_y = y + kPad;
  for (const LegendEntry& e : entries) {
    draw_swatch(canvas, x + kPad, row_y, e, scale);
    canvas.text(x + kPad + kSwatchPx + kSwatchGap, row_y, e.label, kLabel, scale);
    row_y += row_height(scale);
  }
  return box;
}

int legend_row_width(const std::vector<LegendEntry>& entries, int scale) {
  int w = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i > 0) w += 3 * kGlyphAdvance * scale;  // three blanks between entries
    w += entry_width(entries[i], scale);
  }
  return w;
}

Rect draw_legend_row(Canvas& canvas, int x, int y, const std::vector<LegendEntry>& entries, int scale) {
  int cx = x;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i > 0) cx += 3 * kGlyphAdvance * scale;
    draw_swatch(canvas, cx, y, entries[i], scale);
    cx += kSwatchPx + kSwatchGap;
    cx += canvas.text(cx, y, entries[i].label, kLabel, scale);
  }
  return Rect{x, y, cx - x, entries.empty() ? 0 : text_height(scale)};
}

Rect draw_text_lines(Canvas& canvas, int x, int y, const std::vector<std::string>& lines, Rgb c, int scale) {
  int w = 0;
  int line_y = y;
  for (const std::string& line : lines) {
    const bool heading = line.rfind("# ", 0) == 0;
    const std::string_view text = heading ? std::string_view(line).substr(2) : std::string_view(line);
    w = std::max(w, canvas.text(x, line_y, text, c, scale, heading));
    line_y += row_height(scale);
  }
  const int n = static_cast<int>(lines.size());
  return Rect{x, y, w, n > 0 ? (n - 1) * row_height(scale) + text_height(scale) : 0};
}

}  // namespace rtfuse::apps
