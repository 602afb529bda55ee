#pragma once
// What the pictures of a grid share (the map's, the navigator's): the
// page with its title, the view in metres at equal scale, the column of
// legend and key figures beside it, the colours of paper, ink and unknown
// cells, and a cell drawn as the rectangle between its corners' pixels, at
// least one pixel, so cells of a fraction of a pixel fall on the same
// pixel and the one drawn last shows.
#include <string>
#include <vector>

#include "apps/canvas.hpp"
#include "apps/legend.hpp"
#include "apps/plot_axes.hpp"

namespace rtfuse::apps {

inline constexpr int kGridFigureScale = 2;
inline constexpr Rect kGridFigureView{110, 80, 760, 760};
inline constexpr int kGridFigureColumnX = 930;  // the legend and the figures
inline constexpr Rgb kGridFigurePaper{255, 255, 255};
inline constexpr Rgb kGridFigureInk{0, 0, 0};
inline constexpr Rgb kGridFigureUnknown{205, 205, 205};

struct GridPlacement {
  double origin_x = 0.0, origin_y = 0.0;  // the lower-left corner of cell (0, 0)
  double resolution = 0.05;               // m per cell
};

void fill_grid_cell(Canvas& canvas, const Axes& axes, const GridPlacement& grid, int i, int j, Rgb colour);

// A blank page with its title.
Canvas grid_figure_page(const std::string& title);
// The view over x and y in metres, equal scale, its grid drawn.
Axes grid_figure_axes(Canvas& canvas, const Range& x, const Range& y);
// The legend and the key figures beside the view, then the PNG written.
bool finish_grid_figure(Canvas& canvas, const std::vector<LegendEntry>& legend,
                        const std::vector<std::string>& figures, const std::string& path, std::string* error);

}  // namespace rtfuse::apps
