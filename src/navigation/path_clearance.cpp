#include "navigation/path_clearance.hpp"

#include <algorithm>
#include <cmath>

namespace rtfuse::navigation {

namespace {

// A point in fixed point: 2^-bits of a cell, from the grid's origin. The
// follower's points are not cell centres (the nearest point, the cut at
// the check distance), and walking between the centres of their cells, as
// grid_line.hpp does for the planner's cells, can pass a cell the piece
// itself misses and miss one it crosses; so the pieces are walked as they
// are, with exact integer decisions (the same cells on every machine).
struct ClearanceFixed {
  std::int64_t u = 0;
  std::int64_t v = 0;
};

struct ClearanceGrid {
  const CostView& costs;
  const GridGeometry& geometry;
  int bits;             // fraction bits: width and height times 2^bits within 2^30
  std::int64_t scale;   // 2^bits
  std::uint8_t lethal_from;
};

// The fixed point of p, or false when p is outside the grid (or not
// usable). The scale is a power of two, so u * scale is exact and the cell
// of the fixed point is the cell of p.
bool clearance_fixed(const ClearanceGrid& g, Point2 p, ClearanceFixed* out) noexcept {
  if (!usable(p)) return false;
  const double u = (p.x - g.geometry.origin_x) / g.geometry.resolution;
  const double v = (p.y - g.geometry.origin_y) / g.geometry.resolution;
  if (!(u >= 0.0 && v >= 0.0 && u < static_cast<double>(g.costs.width) && v < static_cast<double>(g.costs.height))) {
    return false;
  }
  const double s = static_cast<double>(g.scale);
  *out = ClearanceFixed{static_cast<std::int64_t>(std::floor(u * s)), static_cast<std::int64_t>(std::floor(v * s))};
  return true;
}

// For a >= 0, b > 0.
std::int64_t clearance_floor_div(std::int64_t a, std::int64_t b) noexcept { return a / b; }
std::int64_t clearance_ceil_div(std::int64_t a, std::int64_t b) noexcept { return (a + b - 1) / b; }

// Whether any of rows [r0, r1] of column c blocks (clamped to the grid:
// a closed square on the grid's edge has neighbours that do not exist).
bool clearance_column_blocked(const ClearanceGrid& g, std::int64_t c, std::int64_t r0, std::int64_t r1) noexcept {
  if (c < 0 || c >= g.costs.width) return false;
  r0 = std::max<std::int64_t>(r0, 0);
  r1 = std::min<std::int64_t>(r1, g.costs.height - 1);
  for (std::int64_t r = r0; r <= r1; ++r) {
    if (g.costs.at(static_cast<int>(c), static_cast<int>(r)) >= g.lethal_from) return true;
  }
  return false;
}

// Whether a cell whose closed square the segment from a to b meets blocks:
// column by column, the rows the segment spans within the column's closed
// x range. Closed squares, so a piece along a cell border or through a
// corner counts the cells on both sides (what a centre on the border
// would touch). Both ends are in the grid, so all of it is.
bool clearance_piece_blocked(const ClearanceGrid& g, ClearanceFixed a, ClearanceFixed b) noexcept {
  if (b.u < a.u) std::swap(a, b);
  const std::int64_t s = g.scale;
  const std::int64_t c0 = clearance_ceil_div(a.u, s) - 1;
  const std::int64_t c1 = clearance_floor_div(b.u, s);
  const std::int64_t dx = b.u - a.u;
  if (dx == 0) {
    const std::int64_t r0 = clearance_ceil_div(std::min(a.v, b.v), s) - 1;
    const std::int64_t r1 = clearance_floor_div(std::max(a.v, b.v), s);
    for (std::int64_t c = c0; c <= c1; ++c) {
      if (clearance_column_blocked(g, c, r0, r1)) return true;
    }
    return false;
  }
  // Within the column, y runs between its values at the clipped ends:
  // y(u) = (a.v dx + (u - a.u) dy) / dx, kept as that numerator over dx
  // (at most 2^61: every coordinate is within 2^30).
  const std::int64_t dy = b.v - a.v;
  const std::int64_t den = dx * s;
  for (std::int64_t c = c0; c <= c1; ++c) {
    const std::int64_t ua = std::max(c * s, a.u);
    const std::int64_t ub = std::min((c + 1) * s, b.u);
    if (ua > ub) continue;
    const std::int64_t na = a.v * dx + (ua - a.u) * dy;
    const std::int64_t nb = a.v * dx + (ub - a.u) * dy;
    const std::int64_t r0 = clearance_ceil_div(std::min(na, nb), den) - 1;
    const std::int64_t r1 = clearance_floor_div(std::max(na, nb), den);
    if (clearance_column_blocked(g, c, r0, r1)) return true;
  }
  return false;
}

}  // namespace

bool path_blocked(const CostView& costs, const GridGeometry& geometry, const Point2* path, int n, int from_index,
                  Point2 from, double check_distance_m, std::uint8_t lethal_from) noexcept {
  if (!costs.valid() || path == nullptr || n < 1 || from_index < 0 || from_index >= n || lethal_from == 0) return true;
  if (!(std::isfinite(geometry.resolution) && geometry.resolution > 0.0) || !std::isfinite(geometry.origin_x) ||
      !std::isfinite(geometry.origin_y) || std::isnan(check_distance_m)) {
    return true;
  }
  int side_bits = 0;  // the grid's larger side is at most 2^side_bits cells
  while (side_bits < 31 && (std::int64_t{1} << side_bits) < std::max(costs.width, costs.height)) ++side_bits;
  if (side_bits > 30) return true;
  const int bits = std::min(20, 30 - side_bits);
  const ClearanceGrid g{costs, geometry, bits, std::int64_t{1} << bits, lethal_from};

  ClearanceFixed fa;
  if (!clearance_fixed(g, from, &fa) || clearance_piece_blocked(g, fa, fa)) return true;
  Point2 a = from;
  double left = check_distance_m > 0.0 ? check_distance_m : 0.0;
  for (int i = from_index + 1; i < n && left > 0.0; ++i) {
    Point2 b = path[i];
    if (!usable(b)) return true;
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double length = std::sqrt(dx * dx + dy * dy);
    if (length > left) {  // the last piece, cut where the distance ends
      const double t = left / length;
      b = Point2{a.x + t * dx, a.y + t * dy};
    }
    ClearanceFixed fb;
    if (!clearance_fixed(g, b, &fb) || clearance_piece_blocked(g, fa, fb)) return true;
    left -= length;
    a = b;
    fa = fb;
  }
  return false;
}

}  // namespace rtfuse::navigation
