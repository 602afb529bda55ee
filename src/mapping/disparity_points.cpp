#include "mapping/disparity_points.hpp"

namespace rtfuse::mapping {

DisparityPointCounts disparity_points(const vision::DisparityImage& disparity, int downscale,
                                      const vision::StereoCameraModel& camera,
                                      const geometry::RigidTransform& map_T_camera, MapPoint* out,
                                      std::size_t capacity) noexcept {
  DisparityPointCounts counts;
  if (!disparity.valid()) return counts;
  const std::size_t pixels = static_cast<std::size_t>(disparity.width) * static_cast<std::size_t>(disparity.height);
  const bool usable = camera.f > 0.0 && camera.baseline > 0.0 && downscale >= 1;
  if (!usable) {
    counts.invalid = static_cast<std::uint32_t>(pixels);
    return counts;
  }
  // Plain multiplies and adds in double, written out: the build never
  // contracts them, so both architectures give the same floats.
  const Eigen::Matrix3d r = map_T_camera.rotation_matrix();
  const Eigen::Vector3d t = map_T_camera.translation;
  const double fb = camera.f * camera.baseline * vision::kDisparityScale;  // Z = fb / raw value
  const double inv_f = 1.0 / camera.f;
  const double centre = 0.5 * (downscale - 1);  // the block's centre in input pixels
  std::size_t n = 0;
  for (int v = 0; v < disparity.height; ++v) {
    const std::uint16_t* row = disparity.row(v);
    const double y_ray = (v * downscale + centre - camera.cv) * inv_f;
    for (int u = 0; u < disparity.width; ++u) {
      const std::uint16_t d = row[u];
      if (d == vision::kInvalidDisparity) {
        ++counts.invalid;
        continue;
      }
      if (d == 0) {
        ++counts.at_infinity;
        continue;
      }
      if (n == capacity) {
        ++counts.truncated;
        continue;
      }
      const double z = fb / d;
      const double x = (u * downscale + centre - camera.cu) * inv_f * z;
      const double y = y_ray * z;
      out[n].x = static_cast<float>(r(0, 0) * x + r(0, 1) * y + r(0, 2) * z + t.x());
      out[n].y = static_cast<float>(r(1, 0) * x + r(1, 1) * y + r(1, 2) * z + t.y());
      out[n].z = static_cast<float>(r(2, 0) * x + r(2, 1) * y + r(2, 2) * z + t.z());
      ++n;
    }
  }
  counts.points = static_cast<std::uint32_t>(n);
  return counts;
}

}  // namespace rtfuse::mapping
