#pragma once
// The world the simulated stereo camera sees: a textured floor, walls
// around the area the scenarios drive in, boxes standing between that area
// and the walls, one plain wall, and a sky above the walls. Every surface is
// a planar rectangle, so a ray meets it with a dot product and a divide.
//
// Frames: the world is the simulator's odom frame (z up; a drive starts at
// the origin facing +x). The default free area holds every drive of
// config/scenarios with at least 1.5 m to spare (their union spans x in
// [-4.5, 16.9], y in [-4.8, 17.2]); nothing stands inside it but the
// obstacles a scenario places there (pillars, boxes, the two sides of a
// narrow passage: [[obstacle]] in the scenario, for the mapper to find).
// The world knows where it is solid (solid_in), so a map can be scored
// against the truth.
//
// Texture is what a feature detector at VGA needs: high contrast at every
// scale and nothing periodic. Each surface gets its own image, a "dead
// leaves" pattern of random grey rectangles from a couple of metres down to
// a few centimetres with a fine grain on top, sized to the surface so it
// never repeats, and prefiltered into a mip chain (mip_texture.hpp).
//
// The world is a pure function of its config: the layout and every texel
// come from integer hashing of the seed (sim/counter_rng.hpp), without
// libm, so the same seed builds the same bytes on every machine. Built once
// at start-up (the default world: about 0.1 s and 5 MB of textures);
// read-only afterwards, so any number of renderers may share it.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim/mip_texture.hpp"
#include "sim/obstacle_box.hpp"

namespace rtfuse::sim {

enum class WallSide : std::uint8_t { kMinX, kMaxX, kMinY, kMaxY };


struct CameraWorldConfig {
  std::uint64_t seed = 1;
  // The free area the robot drives in, odom frame, metres.
  double min_x = -6.0, max_x = 18.5;
  double min_y = -6.5, max_y = 19.0;
  // From the free area out to the walls; the boxes stand in this band.
  double wall_margin_m = 3.0;
  double wall_height_m = 2.5;
  int box_count = 12;
  // The textureless wall (the "plain wall" case of visual odometry: facing
  // it, a camera sees nothing to track but the boxes before it). The
  // default is on the robot's right at the start of every drive.
  WallSide plain_wall = WallSide::kMinY;
  // Solids inside the free area (a scenario's [[obstacle]]s), at most
  // kMaxObstacles: after the floor, the walls and the boxes, five faces each.
  std::vector<ObstacleBox> obstacles;
  static constexpr int kMaxObstacles = 12;
};

enum class SurfaceKind : std::uint8_t { kGround, kWall, kPlainWall, kBox };

// A rectangle: the points origin + a * axis_u + b * axis_v for a in
// [0, size_u], b in [0, size_v]. Seen from the side normal points to
// (axis_u x axis_v); from behind it is invisible, as a face of a closed
// solid is.
struct WorldSurface {
  SurfaceKind kind = SurfaceKind::kGround;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();  // unit
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();  // unit, orthogonal to axis_u
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double size_u = 1.0, size_v = 1.0;  // metres
  double texel_m = 0.02;              // texture texel size on the surface
  int texture = -1;                   // index of the texture; -1: plain
  float plain_luma = 0.0f;            // a plain surface's grey
  float shade = 1.0f;                 // light falling on it: luma = texture grey * shade
};

class CameraWorld {
 public:
  static constexpr int kMaxSurfaces = 128;

  explicit CameraWorld(const CameraWorldConfig& config = {});

  const CameraWorldConfig& config() const noexcept { return config_; }
  int surface_count() const noexcept { return static_cast<int>(surfaces_.size()); }
  const WorldSurface& surface(int i) const noexcept { return surfaces_[static_cast<std::size_t>(i)]; }
  const MipTexture& texture(int i) const noexcept { return textures_[static_cast<std::size_t>(i)]; }
  int box_count() const noexcept { return box_count_; }
  // Whether anything solid (a box, an obstacle, the space behind a wall)
  // overlaps the box [x0, x1] x [y0, y1] x [z0, z1]: the truth a map's cell
  // is scored against.
  bool solid_in(double x0, double y0, double x1, double y1, double z0, double z1) const noexcept;

  // The walls' inner faces: the free area grown by the margin.
  double wall_min_x() const noexcept { return config_.min_x - config_.wall_margin_m; }
  double wall_max_x() const noexcept { return config_.max_x + config_.wall_margin_m; }
  double wall_min_y() const noexcept { return config_.min_y - config_.wall_margin_m; }
  double wall_max_y() const noexcept { return config_.max_y + config_.wall_margin_m; }

  // What a ray that meets no surface sees below the horizon (from above the
  // walls, or from outside them): the floor's average grey, as if it went on
  // for ever, so that the horizon stays where it is whatever the walls' height.
  float far_ground_luma() const noexcept { return far_ground_luma_; }

  // The sky's grey for a ray whose elevation has sine `up` (clamped to [0, 1]):
  // brightest at the horizon, a smooth gradient without texture.
  static float sky_luma(float up) noexcept {
    const float e = up < 0.0f ? 0.0f : (up > 1.0f ? 1.0f : up);
    return kSkyHorizonLuma + (kSkyZenithLuma - kSkyHorizonLuma) * e;
  }
  static constexpr float kSkyHorizonLuma = 225.0f;
  static constexpr float kSkyZenithLuma = 185.0f;

 private:
  void add_surface(WorldSurface s, std::uint64_t texture_stream, int max_scale_texels);
  void add_boxes();
  void add_obstacles();
  // A box of four sides and a top: centre on the floor, unit axes ex and
  // ey (ey = z x ex), half sizes a and b; its faces' textures are streams
  // texture_stream .. texture_stream + 4.
  void add_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& ex, double a, double b, double height,
               std::uint64_t texture_stream);

  struct Solid {
    Eigen::Vector3d centre, ex;
    double a, b, height;
  };

  CameraWorldConfig config_;
  std::vector<WorldSurface> surfaces_;
  std::vector<MipTexture> textures_;
  int box_count_ = 0;
  std::vector<Solid> solids_;  // boxes and obstacles, for solid_in()
  float far_ground_luma_ = 0.0f;
};

// The texture generator, exposed for tests: width x height grey texels of
// dead leaves (rectangles from max_scale texels down to 2), a pure function
// of (seed, stream).
std::vector<std::uint8_t> dead_leaves_texture(int width, int height, int max_scale, std::uint64_t seed,
                                              std::uint64_t stream);

}  // namespace rtfuse::sim
