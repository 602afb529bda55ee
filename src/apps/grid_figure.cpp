#include "apps/grid_figure.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::apps {

void fill_grid_cell(Canvas& canvas, const Axes& axes, const GridPlacement& g, int i, int j, Rgb colour) {
  const PointPx a = axes.to_px({g.origin_x + i * g.resolution, g.origin_y + j * g.resolution});
  const PointPx b = axes.to_px({g.origin_x + (i + 1) * g.resolution, g.origin_y + (j + 1) * g.resolution});
  const int x0 = static_cast<int>(std::floor(std::min(a.x, b.x)));
  const int y0 = static_cast<int>(std::floor(std::min(a.y, b.y)));
  const int x1 = std::max(x0 + 1, static_cast<int>(std::floor(std::max(a.x, b.x))));
  const int y1 = std::max(y0 + 1, static_cast<int>(std::floor(std::max(a.y, b.y))));
  canvas.fill_rect({x0, y0, x1 - x0, y1 - y0}, colour);
}

Canvas grid_figure_page(const std::string& title) {
  Canvas canvas(1400, 920, kGridFigurePaper);
  canvas.text(kGridFigureView.x, 20, title, kGridFigureInk, kGridFigureScale, true);
  return canvas;
}

Axes grid_figure_axes(Canvas& canvas, const Range& x, const Range& y) {
  AxesOptions options;
  options.equal_aspect = true;
  options.x_title = "x [m]";
  options.y_title = "y [m]";
  const Axes axes(kGridFigureView, x, y, options);
  axes.draw_grid(canvas);
  return axes;
}

bool finish_grid_figure(Canvas& canvas, const std::vector<LegendEntry>& legend,
                        const std::vector<std::string>& figures, const std::string& path, std::string* error) {
  const Rect box = draw_legend(canvas, kGridFigureColumnX, kGridFigureView.y, legend, kGridFigureScale);
  draw_text_lines(canvas, kGridFigureColumnX, box.bottom() + 30, figures, kGridFigureInk, kGridFigureScale);
  return write_png(canvas, path, error);
}

}  // namespace rtfuse::apps
