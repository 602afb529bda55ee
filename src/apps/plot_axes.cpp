#include "apps/plot_axes.hpp"

#include <algorithm>
#include <cmath>

#include "apps/bitmap_font.hpp"
#include "apps/nice_ticks.hpp"

namespace rtfuse::apps {
namespace {

constexpr int kTickPx = 5;   // length of a tick mark outside the frame
constexpr int kLabelGap = 8;  // frame to tick label

// Something to draw for any data: no range, or one of a single value,
// would make the scale infinite.
Range drawable(Range r) {
  if (r.empty() || !std::isfinite(r.lo) || !std::isfinite(r.hi)) return Range{-1.0, 1.0};
  if (!(r.hi - r.lo > 1e-9 * std::max(1.0, std::abs(r.lo)))) {
    const double half = std::max(0.5, 1e-6 * std::abs(r.lo));
    return Range{r.lo - half, r.hi + half};
  }
  return r;
}

Range widen(Range r, double lo_fraction, double hi_fraction) {
  const double span = r.hi - r.lo;
  return Range{r.lo - lo_fraction * span, r.hi + hi_fraction * span};
}

// The range rounded out to whole steps.
Range to_ticks(Range r, double step) {
  return Range{std::floor(r.lo / step + 1e-9) * step, std::ceil(r.hi / step - 1e-9) * step};
}

int widest_label(const std::vector<double>& ticks, double step, int scale) {
  int w = 0;
  for (const double t : ticks) w = std::max(w, text_width(tick_label(t, step), scale));
  return w;
}

// Whether labels at this step keep a glyph's gap to their neighbours: side
// by side (x) they need their width, stacked (y) their height.
bool labels_fit(double step, Range r, double px_per_unit, int scale, bool horizontal) {
  const int extent = horizontal ? widest_label(tick_values(r.lo, r.hi, step), step, scale) : text_height(scale);
  return step * px_per_unit >= extent + kGlyphAdvance * scale;
}

// Equal aspect: the range is fixed, the step grows until the labels fit.
double step_for_labels(double step, Range r, double px_per_unit, int scale, bool horizontal) {
  for (int i = 0; i < 30 && !labels_fit(step, r, px_per_unit, scale, horizontal); ++i) step = next_nice_step(step);
  return step;
}

// One axis on its own: the range rounded out to whole steps over `px`
// pixels, the step the finest 1-2-5 one at least min_px apart whose labels
// fit once the rounding has shrunk the scale.
Range fit_axis(Range r, double px, int min_px, double min_step, int scale, bool horizontal, double* step) {
  *step = nice_step(r.hi - r.lo, static_cast<int>(px) / min_px);
  if (min_step > 0.0) *step = std::max(*step, nice_step_at_least(min_step));
  Range ticks = to_ticks(r, *step);
  for (int i = 0; i < 30 && !labels_fit(*step, ticks, px / (ticks.hi - ticks.lo), scale, horizontal); ++i) {
    *step = next_nice_step(*step);
    ticks = to_ticks(r, *step);
  }
  return ticks;
}

}  // namespace

void Range::include(double v) noexcept {
  if (!std::isfinite(v)) return;
  lo = std::min(lo, v);
  hi = std::max(hi, v);
}

Axes::Axes(const Rect& area, Range x, Range y, const AxesOptions& options)
    : area_{area.x, area.y, std::max(2, area.w), std::max(2, area.h)}, options_(options) {
  const double w = area_.w - 1, h = area_.h - 1;  // pixel centres from first to last
  const int min_px = std::max(1, options_.min_px_per_tick);
  x = widen(drawable(x), options_.pad_fraction, options_.pad_fraction);
  if (options_.y_from_zero) {
    const bool none = y.empty() || !std::isfinite(y.lo) || !std::isfinite(y.hi);
    const double lo = none ? 0.0 : std::min(0.0, y.lo);
    const double top = none ? 0.0 : std::max(0.0, y.hi);
    const double hi = top - lo > 1e-12 ? top : lo + 1.0;  // all at zero: still a unit to show
    y = Range{lo, hi + (hi - lo) * options_.pad_fraction};
  } else {
    y = widen(drawable(y), options_.pad_fraction, options_.pad_fraction);
  }
  if (options_.equal_aspect) {
    // The scale that fits both spans; the other range widened about its
    // centre (or upwards from zero) to fill the area at that scale.
    const double s = std::min(w / (x.hi - x.lo), h / (y.hi - y.lo));
    const double xc = 0.5 * (x.lo + x.hi), yc = 0.5 * (y.lo + y.hi);
    x = Range{xc - 0.5 * w / s, xc + 0.5 * w / s};
    y = options_.y_from_zero ? Range{y.lo, y.lo + h / s} : Range{yc - 0.5 * h / s, yc + 0.5 * h / s};
    // One step on both axes: the grid is made of squares.
    double step = nice_step_at_least(min_px / s);
    step = step_for_labels(step, x, s, options_.scale, true);
    x_step_ = y_step_ = step;
    sx_ = sy_ = s;
  } else {
    x = fit_axis(x, w, min_px, options_.min_x_step, options_.scale, true, &x_step_);
    y = fit_axis(y, h, min_px, 0.0, options_.scale, false, &y_step_);
    sx_ = w / (x.hi - x.lo);
    sy_ = h / (y.hi - y.lo);
  }
  x_ = x;
  y_ = y;
}

std::vector<double> Axes::x_ticks() const { return tick_values(x_.lo, x_.hi, x_step_); }
std::vector<double> Axes::y_ticks() const { return tick_values(y_.lo, y_.hi, y_step_); }

PointPx Axes::to_px(DataPoint p) const noexcept {
  return PointPx{area_.x + (p.x - x_.lo) * sx_, area_.y + (area_.h - 1) - (p.y - y_.lo) * sy_};
}

void Axes::draw_grid(Canvas& canvas, const AxesStyle& style) const {
  const Rect saved = canvas.clip();
  canvas.set_clip(intersect(area_, saved));
  for (const double t : x_ticks()) {
    const double px = to_px(DataPoint{t, 0.0}).x;
    canvas.line(PointPx{px, static_cast<double>(area_.y)}, PointPx{px, area_.bottom() - 1.0}, style.grid);
  }
  for (const double t : y_ticks()) {
    const double py = to_px(DataPoint{0.0, t}).y;
    canvas.line(PointPx{static_cast<double>(area_.x), py}, PointPx{area_.right() - 1.0, py}, style.grid);
  }
  canvas.set_clip(saved);
  canvas.stroke_rect(area_, style.frame);
}

void Axes::draw_labels(Canvas& canvas, const AxesStyle& style) const {
  const int s = options_.scale;
  const double bottom = area_.bottom() - 1.0, left = area_.x;
  for (const double t : x_ticks()) {
    const double px = to_px(DataPoint{t, 0.0}).x;
    canvas.line(PointPx{px, bottom}, PointPx{px, bottom + kTickPx}, style.frame);
    const std::string label = tick_label(t, x_step_);
    canvas.text(static_cast<int>(std::lround(px)) - text_width(label, s) / 2, area_.bottom() + kLabelGap, label,
                style.text, s);
  }
  for (const double t : y_ticks()) {
    const double py = to_px(DataPoint{0.0, t}).y;
    canvas.line(PointPx{left - kTickPx, py}, PointPx{left, py}, style.frame);
    const std::string label = tick_label(t, y_step_);
    canvas.text(area_.x - kLabelGap - text_width(label, s), static_cast<int>(std::lround(py)) - kCapHeight * s / 2,
                label, style.text, s);
  }
  if (!options_.x_title.empty()) {
    const int w = text_width(options_.x_title, s);
    canvas.text(area_.x + (area_.w - w) / 2, area_.bottom() + kLabelGap + text_height(s) + 4, options_.x_title,
                style.text, s);
  }
  if (!options_.y_title.empty()) canvas.text(y_title_x(), title_line_y(), options_.y_title, style.text, s);
}

int Axes::title_line_y() const noexcept {
  const int s = options_.scale;
  return area_.y - kCapHeight * s / 2 - text_height(s) - 4;  // the top tick's label reaches half a cap above
}

int Axes::y_title_x() const {
  // Above the column of y tick labels.
  return std::max(0, area_.x - kLabelGap - widest_label(y_ticks(), y_step_, options_.scale));
}

int Axes::y_title_end_x() const { return y_title_x() + text_width(options_.y_title, options_.scale); }

void Axes::polyline(Canvas& canvas, const std::vector<DataPoint>& points, Rgb c, int thickness) const {
  std::vector<PointPx> px;
  px.reserve(points.size());
  for (const DataPoint& p : points) px.push_back(to_px(p));
  const Rect saved = canvas.clip();
  canvas.set_clip(intersect(area_, saved));
  canvas.polyline(px, c, thickness);
  canvas.set_clip(saved);
}

void Axes::dashed_line(Canvas& canvas, DataPoint a, DataPoint b, Rgb c, int thickness) const {
  const Rect saved = canvas.clip();
  canvas.set_clip(intersect(area_, saved));
  canvas.dashed_line(to_px(a), to_px(b), c, thickness, 10, 6);
  canvas.set_clip(saved);
}

void Axes::marker(Canvas& canvas, DataPoint p, Marker kind, int radius, Rgb c, int thickness) const {
  const Rect saved = canvas.clip();
  canvas.set_clip(intersect(area_, saved));
  canvas.marker(to_px(p), kind, radius, c, thickness);
  canvas.set_clip(saved);
}

}  // namespace rtfuse::apps
