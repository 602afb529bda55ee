#include "navigation/costmap.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rtfuse::navigation {

namespace {

constexpr int kTile = 16;

// A length in cells; one a rounding away from a whole number is that
// number: 0.15 m at 0.05 m is 3 cells, where the division gives
// 2.9999999999999996 and 3 x 0.05 gives 0.15000000000000002, and a cell
// exactly at the inscribed radius would otherwise fall outside it.
double cells_of(double metres, double resolution) {
  const double x = metres / resolution;
  const double whole = std::round(x);
  return std::fabs(x - whole) <= 1e-9 * std::max(1.0, whole) ? whole : x;
}
enum : std::uint8_t { kFreeKind = 0, kObstacleKind = 1, kUnknownKind = 2 };

}  // namespace

std::string check(const CostmapParams& p) {
  if (!(p.resolution_m > 0.0 && p.resolution_m <= 10.0)) return "resolution must be in (0, 10] m";
  if (!(p.inscribed_radius_m >= 0.0 && p.inscribed_radius_m <= 10.0)) return "inscribed radius must be in [0, 10] m";
  if (!(p.inflation_radius_m >= p.inscribed_radius_m && p.inflation_radius_m <= 10.0)) {
    return "inflation radius must be at least the inscribed radius and at most 10 m";
  }
  if (!(p.cost_scaling_factor >= 0.0 && p.cost_scaling_factor <= 1000.0)) {
    return "cost scaling factor must be in [0, 1000]";
  }
  if (!(std::ceil(cells_of(p.inflation_radius_m, p.resolution_m)) <= 250.0)) {
    return "inflation radius must be at most 250 cells";
  }
  if (p.occupied_from < 1 || p.occupied_from > 100) return "occupied_from must be in [1, 100]";
  return "";
}

Costmap::Costmap(int width, int height, const CostmapParams& params) : width_(width), height_(height), params_(params) {
  const std::string fault = check(params);
  if (!fault.empty()) throw std::invalid_argument("costmap: " + fault);
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    throw std::invalid_argument("costmap: width and height must be in [1, 16384] cells");
  }
  radius_ = static_cast<int>(std::ceil(cells_of(params.inflation_radius_m, params.resolution_m)));
  const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  grid_.reset(new std::int8_t[cells]);
  std::fill(grid_.get(), grid_.get() + cells, std::int8_t{-1});
  kind_.reset(new std::uint8_t[cells]);
  std::fill(kind_.get(), kind_.get() + cells, kUnknownKind);
  cost_.reset(new std::uint8_t[cells]);
  vertical_.reset(new std::uint16_t[cells]);
  // costmap_2d's computeCost, once per squared distance: the costs are a
  // function of the configuration only, so the exp's last bit cannot make
  // two runs differ. Inscribed is decided in cells (d2 against the radius
  // in cells squared), so the rounding of metres cannot open a cell the
  // radius closes.
  const int r2 = radius_ * radius_;
  const double inscribed = cells_of(params.inscribed_radius_m, params.resolution_m);
  cost_at_.reset(new std::uint8_t[static_cast<std::size_t>(r2) + 1]);
  for (int d2 = 0; d2 <= r2; ++d2) {
    const double d = std::sqrt(static_cast<double>(d2));  // in cells
    std::uint8_t c;
    if (d2 == 0) {
      c = kCostLethal;
    } else if (d2 <= inscribed * inscribed * (1.0 + 1e-12)) {
      c = kCostInscribed;
    } else {
      const double factor =
          std::exp(-params.cost_scaling_factor * (d * params.resolution_m - params.inscribed_radius_m));
      c = static_cast<std::uint8_t>((kCostInscribed - 1) * factor);
    }
    cost_at_[static_cast<std::size_t>(d2)] = c;
  }
  tiles_x_ = (width + kTile - 1) / kTile;
  tiles_y_ = (height + kTile - 1) / kTile;
  const std::size_t tiles = static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_);
  dirty_.reset(new std::uint8_t[tiles]());
  dirty_list_.reset(new std::uint32_t[tiles]);
  redo(0, 0, width_, height_);
}

Costmap::~Costmap() = default;

std::uint8_t Costmap::kind_of(std::int8_t value) const noexcept {
  if (value < 0) return kUnknownKind;
  return value >= params_.occupied_from ? kObstacleKind : kFreeKind;
}

void Costmap::set_grid(const std::int8_t* cells) noexcept {
  const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  std::copy(cells, cells + n, grid_.get());
  for (std::size_t i = 0; i < n; ++i) kind_[i] = kind_of(cells[i]);
  redo(0, 0, width_, height_);
  tiles_redone_ = static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_);
}

std::size_t Costmap::update(const std::int8_t* cells) noexcept {
  std::size_t changed = 0;
  std::size_t dirty_count = 0;
  const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  // Blocks of the grid compared as bytes first: a map changes in patches,
  // and most of a 400 x 400 grid is the same from one second to the next.
  constexpr std::size_t kBlock = 64;
  for (std::size_t block = 0; block < n; block += kBlock) {
    const std::size_t end = std::min(n, block + kBlock);
    if (std::equal(cells + block, cells + end, grid_.get() + block)) continue;
    for (std::size_t i = block; i < end; ++i) {
      if (cells[i] == grid_[i]) continue;
      grid_[i] = cells[i];
      const std::uint8_t kind = kind_of(cells[i]);
      if (kind == kind_[i]) continue;
      kind_[i] = kind;
      ++changed;
      // Every tile within the radius of the cell: their costs may follow it.
      const int x = static_cast<int>(i % static_cast<std::size_t>(width_));
      const int y = static_cast<int>(i / static_cast<std::size_t>(width_));
      const int tx0 = std::max(0, x - radius_) / kTile, tx1 = std::min(width_ - 1, x + radius_) / kTile;
      const int ty0 = std::max(0, y - radius_) / kTile, ty1 = std::min(height_ - 1, y + radius_) / kTile;
      for (int ty = ty0; ty <= ty1; ++ty) {
        for (int tx = tx0; tx <= tx1; ++tx) {
          const std::uint32_t t = static_cast<std::uint32_t>(ty * tiles_x_ + tx);
          if (dirty_[t]) continue;
          dirty_[t] = 1;
          dirty_list_[dirty_count++] = t;
        }
      }
    }
  }
  for (std::size_t i = 0; i < dirty_count; ++i) {
    const int t = static_cast<int>(dirty_list_[i]);
    dirty_[static_cast<std::size_t>(t)] = 0;
    const int x0 = (t % tiles_x_) * kTile, y0 = (t / tiles_x_) * kTile;
    redo(x0, y0, std::min(width_, x0 + kTile), std::min(height_, y0 + kTile));
  }
  tiles_redone_ = dirty_count;
  return changed;
}

void Costmap::redo(int x0, int y0, int x1, int y1) noexcept {
  const int r = radius_;
  const std::uint16_t none = static_cast<std::uint16_t>(r + 1);  // no obstacle within the radius
  // The window's columns and the radius beyond them, clipped to the grid:
  // no obstacle further away can reach a cell of the window.
  const int ex0 = std::max(0, x0 - r), ex1 = std::min(width_, x1 + r);
  const int ey0 = std::max(0, y0 - r), ey1 = std::min(height_, y1 + r);
  const auto at = [this](int x, int y) {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
  };
  // First pass, along columns: each window row's distance to the nearest
  // obstacle up or down the column, capped at none.
  for (int x = ex0; x < ex1; ++x) {
    int last = -1000000;  // the row of the last obstacle below
    for (int y = ey0; y < y1; ++y) {
      if (kind_[at(x, y)] == kObstacleKind) last = y;
      if (y >= y0) vertical_[at(x, y)] = static_cast<std::uint16_t>(std::min(y - last, static_cast<int>(none)));
    }
    int next = 1000000;  // the row of the next obstacle above
    for (int y = ey1 - 1; y >= y0; --y) {
      if (kind_[at(x, y)] == kObstacleKind) next = y;
      if (y < y1) {
        const int up = std::min(next - y, static_cast<int>(none));
        if (up < vertical_[at(x, y)]) vertical_[at(x, y)] = static_cast<std::uint16_t>(up);
      }
    }
  }
  // Second pass, along rows: the squared distance to the nearest obstacle
  // is the least (x - x')^2 + vertical(x')^2 over the columns within the
  // radius; its cost from the table, then costmap_2d's rules with the
  // cell's own.
  const int r2 = r * r;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      int best = r2 + 1;
      const int lo = std::max(ex0, x - r), hi = std::min(ex1 - 1, x + r);
      for (int xs = lo; xs <= hi; ++xs) {
        const int v = vertical_[at(xs, y)];
        if (v > r) continue;
        const int d2 = (xs - x) * (xs - x) + v * v;
        best = std::min(best, d2);
      }
      const std::uint8_t inflated = best <= r2 ? cost_at_[static_cast<std::size_t>(best)] : kCostFree;
      const std::uint8_t kind = kind_[at(x, y)];
      std::uint8_t c;
      if (kind == kObstacleKind) {
        c = kCostLethal;
      } else if (kind == kFreeKind) {
        c = inflated;
      } else if (params_.unknown == UnknownCells::kLethal) {
        c = kCostLethal;
      } else if (params_.unknown == UnknownCells::kFree) {
        c = inflated;
      } else {
        c = inflated >= kCostInscribed ? inflated : kCostUnknown;
      }
      cost_[at(x, y)] = c;
    }
  }
}

}  // namespace rtfuse::navigation
