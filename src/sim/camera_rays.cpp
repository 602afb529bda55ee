#include "sim/camera_rays.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rtfuse::sim {

namespace {

constexpr int kMaxNewtonIterations = 50;
constexpr double kConvergedPx = 1e-6;
// Bounds are widened by this much (about 0.03 pixel at VGA) so that float
// rounding in the renderer's tests never culls a surface a ray of the tile
// does hit.
constexpr float kBoundsMargin = 1e-4f;

double radial_factor(const drivers::CameraIntrinsics& k, double r2) noexcept {
  return 1.0 + r2 * (k.k1 + r2 * (k.k2 + r2 * k.k3));
}

// d r_distorted / d r along a ray from the centre (the radial part alone):
// where it turns negative the model folds over and no longer maps one to one.
double radial_slope(const drivers::CameraIntrinsics& k, double r2) noexcept {
  return 1.0 + r2 * (3.0 * k.k1 + r2 * (5.0 * k.k2 + r2 * 7.0 * k.k3));
}

}  // namespace

void distort_normalized(const drivers::CameraIntrinsics& k, double x, double y, double* xd, double* yd) noexcept {
  const double r2 = x * x + y * y;
  const double radial = radial_factor(k, r2);
  *xd = x * radial + 2.0 * k.p1 * x * y + k.p2 * (r2 + 2.0 * x * x);
  *yd = y * radial + k.p1 * (r2 + 2.0 * y * y) + 2.0 * k.p2 * x * y;
}

Undistorted undistort_normalized(const drivers::CameraIntrinsics& k, double xd, double yd) noexcept {
  Undistorted out;
  double x = xd;
  double y = yd;
  const double px_per_unit = std::max(std::abs(k.fx), std::abs(k.fy));
  double err = 0.0;
  for (int it = 0; it <= kMaxNewtonIterations; ++it) {
    double fx = 0.0;
    double fy = 0.0;
    distort_normalized(k, x, y, &fx, &fy);
    const double ex = fx - xd;
    const double ey = fy - yd;
    err = std::sqrt(ex * ex + ey * ey) * px_per_unit;
    out.iterations = it;
    if (err < kConvergedPx * 1e-3) break;  // well inside the tolerance: further steps change nothing
    if (it == kMaxNewtonIterations) break;
    // The Jacobian of the plumb-bob model.
    const double r2 = x * x + y * y;
    const double radial = radial_factor(k, r2);
    const double dradial_dr2 = k.k1 + r2 * (2.0 * k.k2 + r2 * 3.0 * k.k3);
    const double drx = 2.0 * x * dradial_dr2;
    const double dry = 2.0 * y * dradial_dr2;
    const double j11 = radial + x * drx + 2.0 * k.p1 * y + 6.0 * k.p2 * x;
    const double j12 = x * dry + 2.0 * k.p1 * x + 2.0 * k.p2 * y;
    const double j21 = y * drx + 2.0 * k.p1 * x + 2.0 * k.p2 * y;
    const double j22 = radial + y * dry + 6.0 * k.p1 * y + 2.0 * k.p2 * x;
    const double det = j11 * j22 - j12 * j21;
    if (!(std::abs(det) > 1e-12)) break;
    x -= (j22 * ex - j12 * ey) / det;
    y -= (j11 * ey - j21 * ex) / det;
    if (!std::isfinite(x) || !std::isfinite(y)) break;
  }
  out.x = x;
  out.y = y;
  out.residual_px = err;
  out.converged = std::isfinite(x) && std::isfinite(y) && err <= kConvergedPx && radial_slope(k, x * x + y * y) > 0.0;
  return out;
}

bool project_to_pixel(const drivers::CameraIntrinsics& k, const Eigen::Vector3d& p, double* u, double* v) noexcept {
  if (!(p.z() > 0.0)) return false;
  double xd = 0.0;
  double yd = 0.0;
  distort_normalized(k, p.x() / p.z(), p.y() / p.z(), &xd, &yd);
  *u = k.fx * xd + k.cx;
  *v = k.fy * yd + k.cy;
  return true;
}

EyeRays::EyeRays(const drivers::CameraIntrinsics& k, int width, int height)
    : width_(std::max(width, 0)), height_(std::max(height, 0)) {
  tiles_x_ = (width_ + kTile - 1) / kTile;
  tiles_y_ = (height_ + kTile - 1) / kTile;
  const std::size_t pixels = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  x_.resize(pixels);
  y_.resize(pixels);
  length_.resize(pixels);
  inv_length_.resize(pixels);
  tiles_.resize(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_));
  std::size_t next = 0;
  for (int ty = 0; ty < tiles_y_; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      Tile& t = tiles_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_) + static_cast<std::size_t>(tx)];
      t.x0 = tx * kTile;
      t.y0 = ty * kTile;
      t.width = std::min(kTile, width_ - t.x0);
      t.height = std::min(kTile, height_ - t.y0);
      t.first = next;
      for (int y = t.y0; y < t.y0 + t.height; ++y) {
        for (int x = t.x0; x < t.x0 + t.width; ++x) {
          // Pixel centres at integer coordinates, as OpenCV's camera matrix has them.
          const double xd = (static_cast<double>(x) - k.cx) / k.fx;
          const double yd = (static_cast<double>(y) - k.cy) / k.fy;
          const Undistorted u = undistort_normalized(k, xd, yd);
          if (!u.converged) ++unconverged_;
          max_residual_px_ = std::max(max_residual_px_, u.residual_px);
          max_iterations_ = std::max(max_iterations_, u.iterations);
          const double len = std::sqrt(u.x * u.x + u.y * u.y + 1.0);
          x_[next] = static_cast<float>(u.x);
          y_[next] = static_cast<float>(u.y);
          length_[next] = static_cast<float>(len);
          inv_length_[next] = static_cast<float>(1.0 / len);
          ++next;
        }
      }
    }
  }
  for (int ty = 0; ty < tiles_y_; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      tiles_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_) + static_cast<std::size_t>(tx)].bounds =
          bounds_of(tx, ty, tx + 1, ty + 1);
    }
  }
}

EyeRays::Bounds EyeRays::bounds_of(int tx0, int ty0, int tx1, int ty1) const noexcept {
  float x0 = std::numeric_limits<float>::max();
  float y0 = x0;
  float x1 = -x0;
  float y1 = -x0;
  for (int ty = ty0; ty < ty1; ++ty) {
    for (int tx = tx0; tx < tx1; ++tx) {
      const Tile& t = tile(tx, ty);
      for (std::size_t i = t.first; i < t.first + static_cast<std::size_t>(t.width * t.height); ++i) {
        x0 = std::min(x0, x_[i]);
        x1 = std::max(x1, x_[i]);
        y0 = std::min(y0, y_[i]);
        y1 = std::max(y1, y_[i]);
      }
    }
  }
  return Bounds{x0 - kBoundsMargin, x1 + kBoundsMargin, y0 - kBoundsMargin, y1 + kBoundsMargin};
}

}  // namespace rtfuse::sim
