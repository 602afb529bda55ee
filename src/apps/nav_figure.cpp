#include "apps/nav_figure.hpp"

#include <algorithm>
#include <cmath>

#include "apps/grid_figure.hpp"

namespace rtfuse::apps {
namespace {

constexpr Rgb kLethal{0, 0, 0};
constexpr Rgb kInscribed{150, 20, 40};
constexpr Rgb kNavUnknown = kGridFigureUnknown;
constexpr Rgb kTruthBox{0, 150, 60};
constexpr Rgb kPlanned{30, 90, 220};
constexpr Rgb kDriven{220, 40, 40};
constexpr Rgb kGoal{230, 140, 0};

// Inflation from white (0) to a full rose (252), as costmap_2d's viewers shade it.
Rgb cost_colour(std::uint8_t c) noexcept {
  if (c == 255) return kNavUnknown;
  if (c == 254) return kLethal;
  if (c == 253) return kInscribed;
  const double f = static_cast<double>(c) / 252.0;
  const auto mix = [f](int a, int b) { return static_cast<std::uint8_t>(std::lround(a + (b - a) * f)); };
  return Rgb{mix(255, 235), mix(255, 120), mix(255, 140)};
}

}  // namespace

bool write_nav_png(const NavFigure& f, const std::string& path, std::string* error) {
  Canvas canvas = grid_figure_page(f.title);
  // The view: what was known and everything drawn over it.
  Range xr, yr;
  for (int j = 0; j < f.height; ++j) {
    for (int i = 0; i < f.width; ++i) {
      if (f.costs[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.width) + i] == 255) continue;
      xr.include(f.origin_x + i * f.resolution);
      xr.include(f.origin_x + (i + 1) * f.resolution);
      yr.include(f.origin_y + j * f.resolution);
      yr.include(f.origin_y + (j + 1) * f.resolution);
    }
  }
  for (const auto* series : {&f.path, &f.driven, &f.goals}) {
    for (const DataPoint& p : *series) {
      xr.include(p.x);
      yr.include(p.y);
    }
  }
  if (xr.empty() || yr.empty()) {
    xr.include(f.origin_x);
    xr.include(f.origin_x + f.width * f.resolution);
    yr.include(f.origin_y);
    yr.include(f.origin_y + f.height * f.resolution);
  }
  const Axes axes = grid_figure_axes(canvas, xr, yr);
  canvas.set_clip(axes.area());
  // Low costs first, so the higher ones of cells sharing a pixel show.
  const GridPlacement placement{f.origin_x, f.origin_y, f.resolution};
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < f.height; ++j) {
      for (int i = 0; i < f.width; ++i) {
        const std::uint8_t c = f.costs[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.width) + i];
        if ((pass == 0) != (c < 253 || c == 255) || c == 0) continue;
        fill_grid_cell(canvas, axes, placement, i, j, cost_colour(c));
      }
    }
  }
  canvas.reset_clip();
  for (const NavFigure::Box& b : f.obstacles) {
    axes.polyline(canvas, {{b.x0, b.y0}, {b.x1, b.y0}, {b.x1, b.y1}, {b.x0, b.y1}, {b.x0, b.y0}}, kTruthBox, 2);
  }
  axes.polyline(canvas, f.driven, kDriven, 2);
  axes.polyline(canvas, f.path, kPlanned, 2);
  if (!f.driven.empty()) axes.marker(canvas, f.driven.front(), Marker::kCircle, 6, kDriven);
  for (const DataPoint& g : f.goals) axes.marker(canvas, g, Marker::kDisc, 5, kGoal);
  axes.draw_labels(canvas);

  const std::vector<LegendEntry> legend = {
      {"obstacle (254)", kLethal, true, Marker::kSquare, 2, false},
      {"inscribed (253)", kInscribed, true, Marker::kSquare, 2, false},
      {"inflation (1-252)", cost_colour(180), true, Marker::kSquare, 2, false},
      {"unknown (255)", kNavUnknown, true, Marker::kSquare, 2, false},
      {"true obstacle", kTruthBox, false, Marker::kDisc, 2, false},
      {"last path", kPlanned, false, Marker::kDisc, 2, false},
      {"driven (truth)", kDriven, false, Marker::kDisc, 2, false},
      {"start", kDriven, true, Marker::kCircle, 2, false},
      {"goals", kGoal, true, Marker::kDisc, 2, false},
  };
  return finish_grid_figure(canvas, legend, f.figures, path, error);
}

}  // namespace rtfuse::apps
