#include "sim/camera_world.hpp"

#include <algorithm>
#include <cmath>

#include "sim/counter_rng.hpp"

namespace rtfuse::sim {

namespace {

// Stream numbers of sim/counter_rng.hpp for the camera world, away from the
// robot's (0x100..0x3ff).
constexpr std::uint64_t kLayoutStream = 0x4000;
constexpr std::uint64_t kTextureStream = 0x5000;  // + surface index

constexpr double kGroundTexelM = 0.02;
constexpr double kWallTexelM = 0.02;
constexpr double kBoxTexelM = 0.01;
constexpr int kMaxTextureSide = 4096;
constexpr float kPlainWallLuma = 205.0f;

// Uniform in [0, 1), exactly representable: the same on every machine.
double layout_uniform(std::uint64_t seed, std::uint64_t index) noexcept {
  return static_cast<double>(counter_hash(seed, kLayoutStream, index) >> 11) * 0x1.0p-53;
}

// Diffuse light from one direction plus ambient, so that faces meeting at an
// edge (a box's side and top, a wall and the floor) differ in brightness as
// they do under real light.
float shade_of(const Eigen::Vector3d& normal) noexcept {
  const Eigen::Vector3d sun = Eigen::Vector3d(0.5, 0.3, 0.8).normalized();
  const double lit = std::max(0.0, normal.dot(sun));
  return static_cast<float>(0.55 + 0.45 * lit);
}

int largest_power_of_two_at_most(int n) noexcept {
  int p = 1;
  while (p * 2 <= n) p *= 2;
  return p;
}

}  // namespace

std::vector<std::uint8_t> dead_leaves_texture(int width, int height, int max_scale, std::uint64_t seed,
                                              std::uint64_t stream) {
  std::vector<std::uint8_t> img(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 128);
  std::uint64_t index = 0;
  const std::int64_t area = static_cast<std::int64_t>(width) * height;
  // Coarse to fine, finer leaves falling on coarser ones. The coarsest scale
  // covers everything; each finer one covers the fraction that leaves every
  // octave an equal share of the final image (the m-th scale from the
  // coarsest takes 1/m of what the finer ones leave visible: coverage
  // -ln(1 - 1/m), from its series), as in natural images, whose statistics
  // look alike at every scale.
  int m = 1;
  for (int s = std::max(max_scale, 2); s >= 2; s /= 2, ++m) {
    const double x = 1.0 / m;
    const double coverage = m == 1 ? 3.0 : x * (1.0 + x * (0.5 + x * (1.0 / 3.0 + x * 0.25)));
    const auto count = static_cast<std::int64_t>(coverage * static_cast<double>(area) / (static_cast<double>(s) * s)) + 1;
    for (std::int64_t j = 0; j < count; ++j) {
      const std::uint64_t h0 = counter_hash(seed, stream, index++);
      const std::uint64_t h1 = counter_hash(seed, stream, index++);
      const int rw = s / 2 + static_cast<int>(((h0 & 0xFFFF) * static_cast<std::uint64_t>(s)) >> 16);
      const int rh = s / 2 + static_cast<int>((((h0 >> 16) & 0xFFFF) * static_cast<std::uint64_t>(s)) >> 16);
      const int x0 = static_cast<int>((((h0 >> 32) & 0xFFFF) * static_cast<std::uint64_t>(width + rw)) >> 16) - rw;
      const int y0 = static_cast<int>(((h1 & 0xFFFF) * static_cast<std::uint64_t>(height + rh)) >> 16) - rh;
      // High contrast: the whole range but the extremes, which noise and shading would clip.
      const auto grey = static_cast<std::uint8_t>(16 + (((h1 >> 16) & 0xFF) * 224) / 256);
      const int xa = std::max(x0, 0);
      const int xb = std::min(x0 + rw, width);
      const int ya = std::max(y0, 0);
      const int yb = std::min(y0 + rh, height);
      for (int y = ya; y < yb; ++y) {
        std::uint8_t* row = img.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
        std::fill(row + xa, row + std::max(xa, xb), grey);
      }
    }
  }
  // A fine grain (+-7 grey levels per texel), so that even inside the
  // largest leaf a close view has something for block matching to hold on to.
  const std::uint64_t grain_key = counter_hash(seed, stream, ~std::uint64_t{0});
  for (std::size_t i = 0; i < img.size(); ++i) {
    const int g = static_cast<int>(mix64(grain_key + i * 0x9E3779B97F4A7C15ULL) & 15) - 7;
    img[i] = static_cast<std::uint8_t>(std::clamp(img[i] + g, 0, 255));
  }
  return img;
}

CameraWorld::CameraWorld(const CameraWorldConfig& config) : config_(config) {
  config_.wall_margin_m = std::max(config_.wall_margin_m, 0.5);
  config_.wall_height_m = std::max(config_.wall_height_m, 0.1);
  if (!(config_.max_x > config_.min_x)) config_.max_x = config_.min_x + 1.0;
  if (!(config_.max_y > config_.min_y)) config_.max_y = config_.min_y + 1.0;
  surfaces_.reserve(kMaxSurfaces);
  textures_.reserve(kMaxSurfaces);

  const double x0 = wall_min_x();
  const double x1 = wall_max_x();
  const double y0 = wall_min_y();
  const double y1 = wall_max_y();
  const double h = config_.wall_height_m;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d ey = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();

  WorldSurface ground;
  ground.kind = SurfaceKind::kGround;
  ground.origin = Eigen::Vector3d(x0, y0, 0.0);
  ground.axis_u = ex;
  ground.axis_v = ey;
  ground.size_u = x1 - x0;
  ground.size_v = y1 - y0;
  ground.texel_m = kGroundTexelM;
  add_surface(ground, 0, 128);
  const MipTexture& floor = textures_.back();
  far_ground_luma_ = static_cast<float>(floor.texel(floor.levels() - 1, 0, 0)) * surfaces_.back().shade;

  // The walls face inwards, u along the floor, v up.
  struct WallSpec {
    WallSide side;
    Eigen::Vector3d origin, axis_u;
    double length;
  };
  const WallSpec walls[4] = {
      {WallSide::kMinX, Eigen::Vector3d(x0, y0, 0.0), ey, y1 - y0},
      {WallSide::kMaxX, Eigen::Vector3d(x1, y1, 0.0), -ey, y1 - y0},
      {WallSide::kMinY, Eigen::Vector3d(x1, y0, 0.0), -ex, x1 - x0},
      {WallSide::kMaxY, Eigen::Vector3d(x0, y1, 0.0), ex, x1 - x0},
  };
  for (int i = 0; i < 4; ++i) {
    WorldSurface w;
    w.kind = walls[i].side == config_.plain_wall ? SurfaceKind::kPlainWall : SurfaceKind::kWall;
    w.origin = walls[i].origin;
    w.axis_u = walls[i].axis_u;
    w.axis_v = ez;
    w.size_u = walls[i].length;
    w.size_v = h;
    w.texel_m = kWallTexelM;
    w.plain_luma = kPlainWallLuma;
    add_surface(w, 1 + static_cast<std::uint64_t>(i), 128);
  }
  add_boxes();
  add_obstacles();
}

void CameraWorld::add_surface(WorldSurface s, std::uint64_t texture_stream, int max_scale_texels) {
  if (surfaces_.size() >= static_cast<std::size_t>(kMaxSurfaces)) return;
  s.normal = s.axis_u.cross(s.axis_v);
  s.shade = shade_of(s.normal);
  if (s.kind == SurfaceKind::kPlainWall) {
    s.texture = -1;
  } else {
    s.texel_m = std::max({s.texel_m, s.size_u / kMaxTextureSide, s.size_v / kMaxTextureSide});
    const int w = std::max(1, static_cast<int>(std::ceil(s.size_u / s.texel_m)));
    const int hgt = std::max(1, static_cast<int>(std::ceil(s.size_v / s.texel_m)));
    const int scale = std::min(max_scale_texels, largest_power_of_two_at_most(std::min(w, hgt)));
    textures_.emplace_back(w, hgt, dead_leaves_texture(w, hgt, scale, config_.seed, kTextureStream + texture_stream));
    s.texture = static_cast<int>(textures_.size()) - 1;
  }
  surfaces_.push_back(s);
}

void CameraWorld::add_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& ex, double a, double b,
                          double height, std::uint64_t texture_stream) {
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d ey = ez.cross(ex);
  struct Face {
    Eigen::Vector3d origin, u, v;
    double su, sv;
  };
  const Face faces[5] = {
      {centre + a * ex - b * ey, ey, ez, 2.0 * b, height},
      {centre - a * ex + b * ey, -ey, ez, 2.0 * b, height},
      {centre + a * ex + b * ey, -ex, ez, 2.0 * a, height},
      {centre - a * ex - b * ey, ex, ez, 2.0 * a, height},
      {centre - a * ex - b * ey + height * ez, ex, ey, 2.0 * a, 2.0 * b},
  };
  for (int f = 0; f < 5; ++f) {
    WorldSurface w;
    w.kind = SurfaceKind::kBox;
    w.origin = faces[f].origin;
    w.axis_u = faces[f].u;
    w.axis_v = faces[f].v;
    w.size_u = faces[f].su;
    w.size_v = faces[f].sv;
    w.texel_m = kBoxTexelM;
    add_surface(w, texture_stream + static_cast<std::uint64_t>(f), 64);
  }
  solids_.push_back(Solid{centre, ex, a, b, height});
}

void CameraWorld::add_obstacles() {
  // After everything else, with texture streams of their own: a world
  // without obstacles is byte for byte the world it was before they existed.
  const int room = (kMaxSurfaces - static_cast<int>(surfaces_.size())) / 5;
  const int n = std::min({static_cast<int>(config_.obstacles.size()), CameraWorldConfig::kMaxObstacles, room});
  for (int i = 0; i < n; ++i) {
    const ObstacleBox& o = config_.obstacles[static_cast<std::size_t>(i)];
    add_box(Eigen::Vector3d(o.x, o.y, 0.0), Eigen::Vector3d::UnitX(), 0.5 * o.size_x, 0.5 * o.size_y, o.height,
            1024 + static_cast<std::uint64_t>(i) * 5);
  }
}

bool CameraWorld::solid_in(double x0, double y0, double x1, double y1, double z0, double z1) const noexcept {
  if (z1 < 0.0) return false;
  // Behind a wall (up to its height) is solid.
  if (z0 < config_.wall_height_m &&
      (x0 < wall_min_x() || x1 > wall_max_x() || y0 < wall_min_y() || y1 > wall_max_y())) {
    return true;
  }
  // A box against the cell: separated along one of the four axes (x, y and
  // the box's own two) or overlapping.
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const double hx = 0.5 * (x1 - x0), hy = 0.5 * (y1 - y0);
  for (const Solid& b : solids_) {
    if (z0 >= b.height) continue;
    const double ux = b.ex.x(), uy = b.ex.y();  // box axis u; v = (-uy, ux)
    const double dx = b.centre.x() - cx, dy = b.centre.y() - cy;
    const double box_x = b.a * std::abs(ux) + b.b * std::abs(uy);  // the box's half extent along x
    const double box_y = b.a * std::abs(uy) + b.b * std::abs(ux);
    if (std::abs(dx) >= hx + box_x || std::abs(dy) >= hy + box_y) continue;
    const double cell_u = hx * std::abs(ux) + hy * std::abs(uy);
    const double cell_v = hx * std::abs(uy) + hy * std::abs(ux);
    if (std::abs(dx * ux + dy * uy) >= b.a + cell_u || std::abs(-dx * uy + dy * ux) >= b.b + cell_v) continue;
    return true;
  }
  return false;
}

void CameraWorld::add_boxes() {
  // Boxes stand in the band between the free area and the walls, a few per
  // side, not overlapping; each a solid of four sides and a top.
  constexpr int kMaxBoxes = (kMaxSurfaces - 5) / 5;
  constexpr int kTries = 32;
  const int wanted = std::clamp(config_.box_count, 0, kMaxBoxes);
  const double band = config_.wall_margin_m;
  double placed[kMaxBoxes][3];  // centre x, y and footprint radius
  std::uint64_t draw = 0;
  const auto uniform = [&] { return layout_uniform(config_.seed, draw++); };
  for (int i = 0; i < wanted; ++i) {
    for (int attempt = 0; attempt < kTries; ++attempt) {
      double a = 0.2 + 0.4 * uniform();  // half sizes, m
      double b = 0.2 + 0.4 * uniform();
      const double height = 0.3 + 1.3 * uniform();
      // The yaw's cosine and sine from the rational parametrisation of the
      // circle: no libm, so the layout is the same on every machine.
      const double t = 2.0 * uniform() - 1.0;
      const double c = (1.0 - t * t) / (1.0 + t * t);
      const double s = 2.0 * t / (1.0 + t * t);
      const double along = uniform();
      const double across = uniform();
      double radius = std::sqrt(a * a + b * b);
      const double fit = 0.5 * band - 0.1;  // the box must fit across the band
      if (radius > fit) {
        a *= fit / radius;
        b *= fit / radius;
        radius = fit;
      }
      const double depth = radius + 0.05 + (band - 2.0 * radius - 0.1) * across;  // out from the free area
      double cx = 0.0;
      double cy = 0.0;
      switch (i % 4) {
        case 0:  // beyond max_x
          cx = config_.max_x + depth;
          cy = config_.min_y + (config_.max_y - config_.min_y) * along;
          break;
        case 1:  // beyond max_y
          cx = config_.min_x + (config_.max_x - config_.min_x) * along;
          cy = config_.max_y + depth;
          break;
        case 2:  // beyond min_x
          cx = config_.min_x - depth;
          cy = config_.min_y + (config_.max_y - config_.min_y) * along;
          break;
        default:  // beyond min_y, before the plain wall by default
          cx = config_.min_x + (config_.max_x - config_.min_x) * along;
          cy = config_.min_y - depth;
          break;
      }
      bool free = true;
      for (int j = 0; j < box_count_ && free; ++j) {
        const double dx = cx - placed[j][0];
        const double dy = cy - placed[j][1];
        const double r = radius + placed[j][2] + 0.2;
        free = dx * dx + dy * dy > r * r;
      }
      if (!free) continue;
      placed[box_count_][0] = cx;
      placed[box_count_][1] = cy;
      placed[box_count_][2] = radius;

      add_box(Eigen::Vector3d(cx, cy, 0.0), Eigen::Vector3d(c, s, 0.0), a, b, height,
              16 + static_cast<std::uint64_t>(box_count_) * 5);
      ++box_count_;
      break;
    }
  }
}

}  // namespace rtfuse::sim
