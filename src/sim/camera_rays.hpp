#pragma once
// The viewing rays of one simulated eye: for every raw (distorted) pixel,
// the direction it sees in the eye's optical frame (x right, y down, z
// forward), found once at construction by inverting OpenCV's plumb-bob
// distortion. Rendering then never evaluates the lens model per frame: a
// pixel's ray is a table lookup, and the image comes out distorted exactly
// as a real lens with that calibration would make it, which is what the
// rectification downstream is written to undo.
//
// Rays are stored tile by tile (kTile x kTile pixels, row-major inside a
// tile) with, per tile, the bounds of its rays: the renderer tests each
// surface against a tile's pyramid of rays once per frame instead of
// against each pixel.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "drivers/camera/stereo_calibration.hpp"

namespace rtfuse::sim {

// Normalised image coordinates (z = 1) through the plumb-bob model:
// (x, y) undistorted -> (xd, yd) distorted, as cv::projectPoints does.
void distort_normalized(const drivers::CameraIntrinsics& k, double x, double y, double* xd, double* yd) noexcept;

// The inverse, by Newton's method from (xd, yd). converged is false when
// the iteration did not bring the distorted point back within 1e-6 pixel,
// or landed past the radius where the lens model folds back on itself
// (where d r_distorted / d r <= 0: a real lens has no such pixel).
struct Undistorted {
  double x = 0.0, y = 0.0;
  double residual_px = 0.0;  // |distort(x, y) - (xd, yd)| in pixels
  int iterations = 0;
  bool converged = false;
};
Undistorted undistort_normalized(const drivers::CameraIntrinsics& k, double xd, double yd) noexcept;

// The raw pixel (u, v) at which a point in the optical frame appears;
// false if it is behind the camera (z <= 0).
bool project_to_pixel(const drivers::CameraIntrinsics& k, const Eigen::Vector3d& p, double* u, double* v) noexcept;

class EyeRays {
 public:
  static constexpr int kTile = 16;

  // The bounds of a set of rays on the plane z = 1: every ray (x, y, 1) of
  // the set has x in [x0, x1] and y in [y0, y1], so the rays lie in the
  // pyramid of those four planes through the eye's centre.
  struct Bounds {
    float x0 = 0.0f, x1 = 0.0f, y0 = 0.0f, y1 = 0.0f;
  };
  struct Tile {
    int x0 = 0, y0 = 0, width = 0, height = 0;  // pixels
    std::size_t first = 0;                      // index of its first ray
    Bounds bounds;
  };

  EyeRays(const drivers::CameraIntrinsics& k, int width, int height);

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  int tiles_x() const noexcept { return tiles_x_; }
  int tiles_y() const noexcept { return tiles_y_; }
  const Tile& tile(int tx, int ty) const noexcept {
    return tiles_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_) + static_cast<std::size_t>(tx)];
  }
  // Per pixel, tile by tile: the ray (x, y, 1), its length and inverse
  // length, as floats for the renderer (arrays apart so its loops vectorise).
  const float* x() const noexcept { return x_.data(); }
  const float* y() const noexcept { return y_.data(); }
  const float* length() const noexcept { return length_.data(); }
  const float* inv_length() const noexcept { return inv_length_.data(); }
  // The bounds of a rectangle of tiles [tx0, tx1) x [ty0, ty1).
  Bounds bounds_of(int tx0, int ty0, int tx1, int ty1) const noexcept;

  // The lens inversion over every pixel: all converged, and the worst residual.
  bool converged() const noexcept { return unconverged_ == 0; }
  int unconverged_pixels() const noexcept { return unconverged_; }
  double max_residual_px() const noexcept { return max_residual_px_; }
  int max_iterations() const noexcept { return max_iterations_; }

 private:
  int width_ = 0, height_ = 0;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> x_, y_, length_, inv_length_;
  std::vector<Tile> tiles_;
  int unconverged_ = 0;
  double max_residual_px_ = 0.0;
  int max_iterations_ = 0;
};

}  // namespace rtfuse::sim
