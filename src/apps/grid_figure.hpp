#pragma once
// What the pictures of a grid share (the map's, the navigator's): their
// layout on the page, and a cell drawn as the rectangle between its
// corners' pixels, at least one pixel, so cells of a fraction of a pixel
// fall on the same pixel and the one drawn last shows.
#include "apps/canvas.hpp"
#include "apps/plot_axes.hpp"

namespace rtfuse::apps {

inline constexpr int kGridFigureScale = 2;
inline constexpr Rect kGridFigureView{110, 80, 760, 760};
inline constexpr int kGridFigureColumnX = 930;  // the legend and the figures

struct GridPlacement {
  double origin_x = 0.0, origin_y = 0.0;  // the lower-left corner of cell (0, 0)
  double resolution = 0.05;               // m per cell
};

void fill_grid_cell(Canvas& canvas, const Axes& axes, const GridPlacement& grid, int i, int j, Rgb colour);

}  // namespace rtfuse::apps
