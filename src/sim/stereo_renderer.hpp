#pragma once
// The simulated stereo camera's image: the camera world (camera_world.hpp)
// seen from a pose by both eyes of a calibrated pair, written as one
// side-by-side YUYV frame (left eye in the left half) as a ZED-like camera
// delivers it over V4L2.
//
// Each eye renders with its own intrinsics including the plumb-bob
// distortion: every raw pixel's ray is precomputed at construction
// (camera_rays.hpp), so the frame is as distorted as the calibration says
// and the rectification downstream has real work to do. The right eye sits
// where the calibration puts it: x_right = R x_left + T.
//
// Per frame: each surface is moved into each eye's frame once and clipped
// to the half-space in front of the eye; each 16 x 16 tile keeps the
// surfaces that face it and that no side of its pyramid of rays separates
// from it; each pixel then takes the nearest of those (a few dot products
// and a divide each), samples its texture trilinearly at the level its
// footprint needs, and adds exposure noise. Rays that meet nothing see the
// sky above the horizon and the floor's average grey below it.
//
// Luma from the world, chroma 128 (grey). Exposure noise is a pure function
// of (noise seed, sequence, pixel): same inputs, same bytes, on any machine
// (floats with + - * / only, integer hashing). render() does not allocate
// and is not thread-safe (it uses the renderer's scratch); one renderer per
// camera thread.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/time.hpp"
#include "drivers/camera/stereo_calibration.hpp"
#include "geometry/rigid_transform.hpp"
#include "sim/camera_rays.hpp"
#include "sim/camera_world.hpp"

namespace rtfuse::sim {

struct StereoRendererOptions {
  std::uint64_t noise_seed = 1;
  double noise_sigma_grey = 2.0;  // per pixel, per frame, grey levels (0: none)
};

// What render() drew, for the caller's frame metadata and for tests.
struct RenderedFrame {
  TimeNs stamp = 0;
  std::uint32_t sequence = 0;
  int sky_pixels = 0;  // both eyes: rays above the horizon that met no surface
};

class StereoRenderer {
 public:
  // `world` must outlive the renderer. Check valid() before rendering.
  StereoRenderer(const drivers::StereoCalibration& calibration, const CameraWorld& world,
                 const StereoRendererOptions& options = {});
  ~StereoRenderer();
  StereoRenderer(const StereoRenderer&) = delete;
  StereoRenderer& operator=(const StereoRenderer&) = delete;

  // False when the calibration cannot be rendered (size, focal lengths) or
  // its distortion could not be inverted at some pixel; error() says why.
  bool valid() const noexcept { return error_ == nullptr; }
  const char* error() const noexcept { return error_; }

  int eye_width() const noexcept { return width_; }
  int eye_height() const noexcept { return height_; }
  int frame_width() const noexcept { return 2 * width_; }  // pixels
  int min_bytes_per_line() const noexcept { return 4 * width_; }  // YUYV: 2 bytes a pixel
  const EyeRays& rays(int eye) const noexcept { return *eyes_[eye].rays; }
  const drivers::StereoCalibration& calibration() const noexcept { return calibration_; }
  // The right eye's optical frame in the left's (from the calibration's R, T).
  const geometry::RigidTransform& left_T_right() const noexcept { return left_T_right_; }

  // Renders the frame seen with the left eye's optical frame at world_T_left
  // (world = the odom frame of the camera world) into out: height rows of
  // bytes_per_line bytes (>= min_bytes_per_line()). Returns false, writing
  // nothing, if the renderer is invalid, out is null or the line too short.
  bool render(const geometry::RigidTransform& world_T_left, TimeNs stamp, std::uint32_t sequence, std::uint8_t* out,
              int bytes_per_line, RenderedFrame* info = nullptr) noexcept;

 private:
  struct FrameSurface;
  struct Eye {
    drivers::CameraIntrinsics intrinsics;
    std::unique_ptr<EyeRays> rays;
    std::vector<EyeRays::Bounds> block_bounds;  // groups of kBlock x kBlock tiles
    int blocks_x = 0, blocks_y = 0;
  };
  static constexpr int kBlock = 4;

  void prepare_surfaces(const geometry::RigidTransform& eye_T_world, const Eye& eye) noexcept;
  int render_eye(int e, std::uint64_t frame_key, std::uint8_t* out, int bytes_per_line) noexcept;

  drivers::StereoCalibration calibration_;
  const CameraWorld& world_;
  StereoRendererOptions options_;
  const char* error_ = nullptr;
  int width_ = 0, height_ = 0;
  geometry::RigidTransform left_T_right_;
  Eye eyes_[2];

  // Per-frame scratch, sized at construction.
  std::vector<FrameSurface> frame_surfaces_;
  int frame_surface_count_ = 0;
  float up_[3] = {0.0f, 0.0f, 0.0f};  // world up in the eye's frame
};

// A rotation vector (axis * angle, radians) as a rotation matrix
// (Rodrigues), with sin and cos from their series: + - * / only, so the
// right eye's pose is the same to the bit on every machine.
Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& r) noexcept;

}  // namespace rtfuse::sim
