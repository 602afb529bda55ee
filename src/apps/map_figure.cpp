#include "apps/map_figure.hpp"

#include <algorithm>
#include <cmath>

#include "apps/grid_figure.hpp"

namespace rtfuse::apps {
namespace {

constexpr Rgb kOccupied{0, 0, 0};
constexpr Rgb kFree{254, 254, 254};
constexpr Rgb kUnknown = kGridFigureUnknown;
constexpr Rgb kPath{220, 40, 40};

}  // namespace

bool write_map_png(const MapFigure& f, const std::string& path, std::string* error) {
  Canvas canvas = grid_figure_page(f.title);
  Range xr, yr;
  xr.include(f.origin_x);
  xr.include(f.origin_x + f.width * f.resolution);
  yr.include(f.origin_y);
  yr.include(f.origin_y + f.height * f.resolution);
  for (const DataPoint& p : f.path) {
    xr.include(p.x);
    yr.include(p.y);
  }
  const Axes axes = grid_figure_axes(canvas, xr, yr);
  // Occupied drawn last, so it shows where cells share a pixel.
  canvas.set_clip(axes.area());
  const GridPlacement placement{f.origin_x, f.origin_y, f.resolution};
  for (const std::int8_t state : {std::int8_t{0}, std::int8_t{-1}, std::int8_t{100}}) {
    const Rgb colour = state == 100 ? kOccupied : state == 0 ? kFree : kUnknown;
    for (int j = 0; j < f.height; ++j) {
      for (int i = 0; i < f.width; ++i) {
        if (f.cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.width) + i] != state) continue;
        fill_grid_cell(canvas, axes, placement, i, j, colour);
      }
    }
  }
  canvas.reset_clip();
  axes.polyline(canvas, f.path, kPath, 2);
  if (!f.path.empty()) axes.marker(canvas, f.path.front(), Marker::kCircle, 6, kPath);
  axes.draw_labels(canvas);

  const std::vector<LegendEntry> legend = {
      {"occupied (black)", kOccupied, true, Marker::kSquare, 2, false},
      {"free (white)", Rgb{150, 150, 150}, true, Marker::kSquare, 1, false},
      {"unknown (grey)", kUnknown, true, Marker::kSquare, 2, false},
      {"sensor path", kPath, false, Marker::kDisc, 2, false},
      {"start", kPath, true, Marker::kCircle, 2, false},
  };
  return finish_grid_figure(canvas, legend, f.figures, path, error);
}

}  // namespace rtfuse::apps
