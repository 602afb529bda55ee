#include "sim/stereo_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/counter_rng.hpp"

namespace rtfuse::sim {

namespace {

constexpr std::uint64_t kExposureStream = 0x6000;
constexpr int kMaxEyeSide = 8192;
constexpr int kTilePixels = EyeRays::kTile * EyeRays::kTile;
// The sum of four uniform 16-bit draws: mean 4 * 65535 / 2, standard
// deviation 65536 / sqrt(3) (Irwin-Hall, close enough to a Gaussian for
// sensor noise, and integer so it is the same everywhere).
constexpr std::int64_t kNoiseMean = 2 * 65535;
constexpr double kNoiseSigma = 37837.23;

constexpr int kMaxClipped = 5;  // a rectangle cut by one plane

}  // namespace

// A surface in the eye's frame for this frame, as the pixel loop wants it.
// A ray t * (x, y, 1) meets the plane n . X = dist at t = dist / (n . d);
// the texel coordinates there are t * (e_u . d) - u0 (e_u: the u axis over
// the texel size).
struct StereoRenderer::FrameSurface {
  float nx = 0, ny = 0, nz = 0, dist = 0;
  float ux = 0, uy = 0, uz = 0, u0 = 0;
  float vx = 0, vy = 0, vz = 0, v0 = 0;
  float umax = 0, vmax = 0;
  // The part of the rectangle in front of the eye (z >= 0), as a polygon.
  int vertex_count = 0;
  float px[kMaxClipped] = {}, py[kMaxClipped] = {}, pz[kMaxClipped] = {};
  float footprint = 0;                      // texels covered by a pixel at depth 1, face on
  float shade = 1, plain_luma = 0;
  const MipTexture* texture = nullptr;
};

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& r) noexcept {
  const double theta2 = r.squaredNorm();
  // sin(t)/t and (1 - cos(t))/t^2 as their series in t^2: converge for every
  // angle, and use no libm.
  double a = 0.0;
  double b = 0.0;
  double term_a = 1.0;
  double term_b = 0.5;
  for (int k = 1; k <= 40; ++k) {
    a += term_a;
    b += term_b;
    term_a *= -theta2 / ((2.0 * k) * (2.0 * k + 1.0));
    term_b *= -theta2 / ((2.0 * k + 1.0) * (2.0 * k + 2.0));
  }
  Eigen::Matrix3d k;
  k << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return Eigen::Matrix3d::Identity() + a * k + b * (k * k);
}

StereoRenderer::StereoRenderer(const drivers::StereoCalibration& calibration, const CameraWorld& world,
                               const StereoRendererOptions& options)
    : calibration_(calibration), world_(world), options_(options) {
  width_ = calibration.width;
  height_ = calibration.height;
  if (width_ <= 0 || height_ <= 0 || width_ > kMaxEyeSide || height_ > kMaxEyeSide) {
    error_ = "stereo calibration: image size out of range";
    width_ = height_ = 0;
  }
  const drivers::CameraIntrinsics* k[2] = {&calibration.left, &calibration.right};
  for (const auto* ki : k) {
    if (!(ki->fx > 0.0 && ki->fy > 0.0 && std::isfinite(ki->cx) && std::isfinite(ki->cy))) {
      error_ = "stereo calibration: focal lengths must be > 0";
    }
  }
  // x_right = R x_left + T: that is right_T_left.
  geometry::RigidTransform right_T_left;
  const Eigen::Matrix3d r = rotation_from_vector(calibration.rotation);
  right_T_left.rotation = Eigen::Quaterniond(r).normalized();
  right_T_left.translation = calibration.translation;
  left_T_right_ = right_T_left.inverse();

  for (int e = 0; e < 2; ++e) {
    Eye& eye = eyes_[e];
    eye.intrinsics = *k[e];
    eye.rays = std::make_unique<EyeRays>(eye.intrinsics, error_ ? 0 : width_, error_ ? 0 : height_);
    if (!error_ && !eye.rays->converged()) {
      error_ = "stereo calibration: the lens distortion cannot be inverted at every pixel (folds over)";
    }
    eye.blocks_x = (eye.rays->tiles_x() + kBlock - 1) / kBlock;
    eye.blocks_y = (eye.rays->tiles_y() + kBlock - 1) / kBlock;
    for (int by = 0; by < eye.blocks_y; ++by) {
      for (int bx = 0; bx < eye.blocks_x; ++bx) {
        eye.block_bounds.push_back(eye.rays->bounds_of(bx * kBlock, by * kBlock,
                                                    std::min((bx + 1) * kBlock, eye.rays->tiles_x()),
                                                    std::min((by + 1) * kBlock, eye.rays->tiles_y())));
      }
    }
  }
  frame_surfaces_.resize(static_cast<std::size_t>(CameraWorld::kMaxSurfaces));
}

StereoRenderer::~StereoRenderer() = default;

void StereoRenderer::prepare_surfaces(const geometry::RigidTransform& eye_T_world, const Eye& eye) noexcept {
  const Eigen::Matrix3d r = eye_T_world.rotation_matrix();
  const Eigen::Vector3d p = eye_T_world.translation;
  const Eigen::Vector3d up = r.col(2);
  up_[0] = static_cast<float>(up.x());
  up_[1] = static_cast<float>(up.y());
  up_[2] = static_cast<float>(up.z());
  const double focal = 0.5 * (eye.intrinsics.fx + eye.intrinsics.fy);
  frame_surface_count_ = 0;
  for (int i = 0; i < world_.surface_count() && i < CameraWorld::kMaxSurfaces; ++i) {
    const WorldSurface& w = world_.surface(i);
    FrameSurface& f = frame_surfaces_[static_cast<std::size_t>(i)];
    const Eigen::Vector3d n = r * w.normal;
    const Eigen::Vector3d o = r * w.origin + p;
    const double dist = n.dot(o);
    // Seen from behind (or edge on): invisible. Marked by dist >= 0, which
    // no pixel's test accepts.
    f.dist = dist < -1e-9 ? static_cast<float>(dist) : 0.0f;
    f.nx = static_cast<float>(n.x());
    f.ny = static_cast<float>(n.y());
    f.nz = static_cast<float>(n.z());
    const Eigen::Vector3d eu = r * w.axis_u / w.texel_m;
    const Eigen::Vector3d ev = r * w.axis_v / w.texel_m;
    f.ux = static_cast<float>(eu.x());
    f.uy = static_cast<float>(eu.y());
    f.uz = static_cast<float>(eu.z());
    f.u0 = static_cast<float>(eu.dot(o));
    f.vx = static_cast<float>(ev.x());
    f.vy = static_cast<float>(ev.y());
    f.vz = static_cast<float>(ev.z());
    f.v0 = static_cast<float>(ev.dot(o));
    f.umax = static_cast<float>(w.size_u / w.texel_m);
    f.vmax = static_cast<float>(w.size_v / w.texel_m);
    // Clip the rectangle to z >= 0 (Sutherland-Hodgman with one plane):
    // every ray has z = 1, so only that part can be hit, and the tiles'
    // pyramid tests are only valid in front of the eye.
    const Eigen::Vector3d du = r * (w.size_u * w.axis_u);
    const Eigen::Vector3d dv = r * (w.size_v * w.axis_v);
    const Eigen::Vector3d corners[4] = {o, o + du, o + du + dv, o + dv};
    f.vertex_count = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& a = corners[k];
      const Eigen::Vector3d& b = corners[(k + 1) % 4];
      if (a.z() >= 0.0) {
        f.px[f.vertex_count] = static_cast<float>(a.x());
        f.py[f.vertex_count] = static_cast<float>(a.y());
        f.pz[f.vertex_count] = static_cast<float>(a.z());
        ++f.vertex_count;
      }
      if ((a.z() >= 0.0) != (b.z() >= 0.0) && f.vertex_count < kMaxClipped) {
        const double s = a.z() / (a.z() - b.z());
        const Eigen::Vector3d m = a + s * (b - a);
        f.px[f.vertex_count] = static_cast<float>(m.x());
        f.py[f.vertex_count] = static_cast<float>(m.y());
        f.pz[f.vertex_count] = 0.0f;
        ++f.vertex_count;
      }
    }
    if (f.vertex_count == 0) f.dist = 0.0f;  // wholly behind the eye
    f.footprint = static_cast<float>(1.0 / (focal * w.texel_m));
    f.shade = w.shade;
    f.plain_luma = w.plain_luma;
    f.texture = w.texture >= 0 ? &world_.texture(w.texture) : nullptr;
    frame_surface_count_ = i + 1;
  }
}

bool StereoRenderer::render(const geometry::RigidTransform& world_T_left, TimeNs stamp, std::uint32_t sequence,
                            std::uint8_t* out, int bytes_per_line, RenderedFrame* info) noexcept {
  if (error_ != nullptr || out == nullptr || bytes_per_line < min_bytes_per_line()) return false;
  const std::uint64_t frame_key = counter_hash(options_.noise_seed, kExposureStream, sequence);
  const geometry::RigidTransform left_T_world = world_T_left.inverse();
  const geometry::RigidTransform right_T_world = left_T_right_.inverse() * left_T_world;
  int sky = 0;
  prepare_surfaces(left_T_world, eyes_[0]);
  sky += render_eye(0, frame_key, out, bytes_per_line);
  prepare_surfaces(right_T_world, eyes_[1]);
  sky += render_eye(1, frame_key, out, bytes_per_line);
  if (info != nullptr) {
    info->stamp = stamp;
    info->sequence = sequence;
    info->sky_pixels = sky;
  }
  return true;
}

int StereoRenderer::render_eye(int e, std::uint64_t frame_key, std::uint8_t* out, int bytes_per_line) noexcept {
  const Eye& eye = eyes_[e];
  const EyeRays& rays = *eye.rays;
  const float* rx = rays.x();
  const float* ry = rays.y();
  const float* rlen = rays.length();
  const float* rinv = rays.inv_length();
  const FrameSurface* surfaces = frame_surfaces_.data();
  const auto noise_scale = static_cast<float>(options_.noise_sigma_grey / kNoiseSigma);
  const bool noisy = options_.noise_sigma_grey > 0.0;
  const float far_ground = world_.far_ground_luma();
  const auto frame_pitch = static_cast<std::uint64_t>(2 * width_);
  int sky_pixels = 0;

  std::uint8_t eye_candidates[CameraWorld::kMaxSurfaces];
  int eye_count = 0;
  for (int s = 0; s < frame_surface_count_; ++s) {
    if (surfaces[s].dist < 0.0f) eye_candidates[eye_count++] = static_cast<std::uint8_t>(s);
  }

  std::uint8_t block_candidates[CameraWorld::kMaxSurfaces];
  std::uint8_t tile_candidates[CameraWorld::kMaxSurfaces];
  alignas(64) float best_t[kTilePixels];
  alignas(64) std::int32_t best_s[kTilePixels];

  // Whether a surface may be seen through a pyramid of rays: not when one
  // of the pyramid's four side planes has the whole (clipped) polygon on
  // its outer side. Conservative: a surface kept may still cover no pixel.
  const auto meets = [](const FrameSurface& f, const EyeRays::Bounds& b) {
    bool left = true, right = true, top = true, bottom = true;
    for (int k = 0; k < f.vertex_count; ++k) {
      left &= f.px[k] < b.x0 * f.pz[k];
      right &= f.px[k] > b.x1 * f.pz[k];
      top &= f.py[k] < b.y0 * f.pz[k];
      bottom &= f.py[k] > b.y1 * f.pz[k];
    }
    return !(left | right | top | bottom);
  };

  for (int by = 0; by < eye.blocks_y; ++by) {
    for (int bx = 0; bx < eye.blocks_x; ++bx) {
      const EyeRays::Bounds& bc = eye.block_bounds[static_cast<std::size_t>(by * eye.blocks_x + bx)];
      int block_count = 0;
      for (int i = 0; i < eye_count; ++i) {
        if (meets(surfaces[eye_candidates[i]], bc)) block_candidates[block_count++] = eye_candidates[i];
      }
      const int tx1 = std::min((bx + 1) * kBlock, rays.tiles_x());
      const int ty1 = std::min((by + 1) * kBlock, rays.tiles_y());
      for (int ty = by * kBlock; ty < ty1; ++ty) {
        for (int tx = bx * kBlock; tx < tx1; ++tx) {
          const EyeRays::Tile& tile = rays.tile(tx, ty);
          int count = 0;
          for (int i = 0; i < block_count; ++i) {
            if (meets(surfaces[block_candidates[i]], tile.bounds)) tile_candidates[count++] = block_candidates[i];
          }
          const int n = tile.width * tile.height;
          const float* x = rx + tile.first;
          const float* y = ry + tile.first;
          for (int i = 0; i < n; ++i) {
            best_t[i] = std::numeric_limits<float>::max();
            best_s[i] = -1;
          }
          // Depth: the nearest surface whose rectangle the ray meets. One
          // branch-free pass per surface so the loop vectorises.
          for (int c = 0; c < count; ++c) {
            const FrameSurface& f = surfaces[tile_candidates[c]];
            const std::int32_t id = tile_candidates[c];
            const float nx = f.nx, ny = f.ny, nz = f.nz, dist = f.dist;
            const float ux = f.ux, uy = f.uy, uz = f.uz, u0 = f.u0, umax = f.umax;
            const float vx = f.vx, vy = f.vy, vz = f.vz, v0 = f.v0, vmax = f.vmax;
            for (int i = 0; i < n; ++i) {
              const float nd = nx * x[i] + ny * y[i] + nz;
              const float t = dist / nd;
              const float u = t * (ux * x[i] + uy * y[i] + uz) - u0;
              const float v = t * (vx * x[i] + vy * y[i] + vz) - v0;
              const bool hit = (nd < 0.0f) & (t < best_t[i]) & (u >= 0.0f) & (u <= umax) & (v >= 0.0f) & (v <= vmax);
              best_t[i] = hit ? t : best_t[i];
              best_s[i] = hit ? id : best_s[i];
            }
          }
          // Shade.
          const float* len = rlen + tile.first;
          const float* inv = rinv + tile.first;
          int i = 0;
          for (int py = tile.y0; py < tile.y0 + tile.height; ++py) {
            std::uint8_t* row = out + static_cast<std::size_t>(py) * static_cast<std::size_t>(bytes_per_line) +
                                2 * static_cast<std::size_t>(e * width_ + tile.x0);
            const std::uint64_t pixel0 =
                static_cast<std::uint64_t>(py) * frame_pitch + static_cast<std::uint64_t>(e * width_ + tile.x0);
            for (int px = 0; px < tile.width; ++px, ++i) {
              float luma = 0.0f;
              if (best_s[i] < 0) {
                const float up = (up_[0] * x[i] + up_[1] * y[i] + up_[2]) * inv[i];
                if (up >= 0.0f) {
                  luma = CameraWorld::sky_luma(up);
                  ++sky_pixels;
                } else {
                  luma = far_ground;
                }
              } else {
                const FrameSurface& f = surfaces[best_s[i]];
                if (f.texture == nullptr) {
                  luma = f.plain_luma * f.shade;
                } else {
                  const float nd = f.nx * x[i] + f.ny * y[i] + f.nz;
                  const float t = best_t[i];
                  const float u = t * (f.ux * x[i] + f.uy * y[i] + f.uz) - f.u0;
                  const float v = t * (f.vx * x[i] + f.vy * y[i] + f.vz) - f.v0;
                  // A pixel's footprint in texels: across the ray t / f,
                  // along the surface's slope that over the cosine of
                  // incidence. The level is their geometric mean, but never
                  // more than 2x finer than the long axis needs: a floor
                  // seen at a grazing angle then neither aliases much nor
                  // blurs sideways into a smear.
                  const float across = t * f.footprint;
                  const float along = across * len[i] / -nd;
                  const float log_along = approx_log2(along);
                  const float log_mean = 0.5f * (log_along + approx_log2(across));
                  const float lod = std::max(log_along - 1.0f, log_mean);
                  luma = f.texture->sample_lod(u, v, lod) * f.shade;
                }
              }
              if (noisy) {
                const std::uint64_t h = mix64(frame_key + (pixel0 + static_cast<std::uint64_t>(px)) * 0x9E3779B97F4A7C15ULL);
                const std::int64_t sum = static_cast<std::int64_t>((h & 0xFFFF) + ((h >> 16) & 0xFFFF) +
                                                                   ((h >> 32) & 0xFFFF) + (h >> 48));
                luma += static_cast<float>(sum - kNoiseMean) * noise_scale;
              }
              luma += 0.5f;
              luma = luma < 0.0f ? 0.0f : (luma > 255.0f ? 255.0f : luma);
              row[2 * px] = static_cast<std::uint8_t>(luma);
              row[2 * px + 1] = 128;
            }
          }
        }
      }
    }
  }
  return sky_pixels;
}

}  // namespace rtfuse::sim
