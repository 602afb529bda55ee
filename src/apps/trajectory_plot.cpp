#include "apps/trajectory_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <png.h>

namespace rtfuse::apps {
namespace {

constexpr int kSize = 800;
constexpr int kMargin = 40;

void plot_path(std::vector<std::uint8_t>& rgb, const std::vector<Eigen::Matrix4d>& path, double x0, double z0,
               double scale, const std::uint8_t colour[3]) {
  auto put = [&](int x, int y) {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int px = x + dx, py = y + dy;
        if (px < 0 || py < 0 || px >= kSize || py >= kSize) continue;
        std::memcpy(&rgb[static_cast<std::size_t>((py * kSize + px) * 3)], colour, 3);
      }
  };
  auto to_px = [&](const Eigen::Matrix4d& t, double* x, double* y) {
    *x = kMargin + (t(0, 3) - x0) * scale;
    *y = kSize - kMargin - (t(2, 3) - z0) * scale;  // forward is up
  };
  for (std::size_t i = 1; i < path.size(); ++i) {
    double ax, ay, bx, by;
    to_px(path[i - 1], &ax, &ay);
    to_px(path[i], &bx, &by);
    const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(bx - ax), std::abs(by - ay)))));
    for (int s = 0; s <= steps; ++s) {
      const double f = static_cast<double>(s) / steps;
      put(static_cast<int>(std::lround(ax + f * (bx - ax))), static_cast<int>(std::lround(ay + f * (by - ay))));
    }
  }
}

}  // namespace

bool write_trajectory_plot(const std::string& path, const std::vector<Eigen::Matrix4d>& estimate,
                           const std::vector<Eigen::Matrix4d>& truth, std::string* error) {
  double xmin = 0, xmax = 0, zmin = 0, zmax = 0;
  for (const auto* list : {&estimate, &truth}) {
    for (const Eigen::Matrix4d& t : *list) {
      xmin = std::min(xmin, t(0, 3)), xmax = std::max(xmax, t(0, 3));
      zmin = std::min(zmin, t(2, 3)), zmax = std::max(zmax, t(2, 3));
    }
  }
  const double span = std::max({xmax - xmin, zmax - zmin, 1.0});
  const double scale = (kSize - 2 * kMargin) / span;
  // Centre the shorter axis.
  const double x0 = xmin - 0.5 * (span - (xmax - xmin));
  const double z0 = zmin - 0.5 * (span - (zmax - zmin));
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(kSize * kSize * 3), 255);
  const std::uint8_t black[3] = {0, 0, 0}, red[3] = {220, 30, 30};
  plot_path(rgb, truth, x0, z0, scale, black);
  plot_path(rgb, estimate, x0, z0, scale, red);
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = kSize;
  image.height = kSize;
  image.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&image, path.c_str(), 0, rgb.data(), 0, nullptr)) {
    *error = path + ": cannot write the plot: " + image.message;
    return false;
  }
  return true;
}

}  // namespace rtfuse::apps
