#include "mapping/keyframe_mapper.hpp"

#include <cmath>
#include <stdexcept>

#include "mapping/brick_store.hpp"
#include "vision/semi_global_matcher.hpp"

namespace rtfuse::mapping {

KeyframeMapper::~KeyframeMapper() = default;

std::uint64_t bricks_for_one_scan(double resolution_m, double max_range_m) noexcept {
  const double brick = resolution_m * (1 << kBrickShift);
  const double r = max_range_m / brick + 1.0;
  return static_cast<std::uint64_t>(std::ceil(3.14159265358979 * r * r)) * 2u;
}

std::unique_ptr<KeyframeMapper> KeyframeMapper::create(int width, int height, const vision::StereoCameraModel& camera,
                                                       const KeyframeMapperParams& params, std::string* error) {
  if (!(camera.f > 0.0) || !(camera.baseline > 0.0) || !std::isfinite(camera.f) || !std::isfinite(camera.baseline)) {
    *error = "the rectified camera has focal length " + std::to_string(camera.f) + " px and baseline " +
             std::to_string(camera.baseline) + " m: depth from disparity needs both positive (check the calibration)";
    return nullptr;
  }
  if (!(params.max_range_m > 0.0) || !std::isfinite(params.max_range_m)) {
    *error = "max_range " + std::to_string(params.max_range_m) + " m must be > 0 and finite";
    return nullptr;
  }
  const std::string bad = check(params.occupancy);
  if (!bad.empty()) {
    *error = bad;
    return nullptr;
  }
  std::unique_ptr<KeyframeMapper> m(new KeyframeMapper());
  m->params_ = params;
  m->camera_ = camera;
  m->width_ = width;
  m->height_ = height;
  m->matcher_ = std::make_unique<vision::SemiGlobalMatcher>(width, height, params.disparity);
  if (!m->matcher_->valid()) {
    *error = std::string("disparity: ") + m->matcher_->error();
    return nullptr;
  }
  m->texture_ = std::make_unique<vision::TextureFilter>(width, height, params.texture);
  m->disparity_width_ = m->matcher_->output_width(width);
  m->disparity_height_ = m->matcher_->output_height(height);
  const std::size_t pixels =
      static_cast<std::size_t>(m->disparity_width_) * static_cast<std::size_t>(m->disparity_height_);
  m->disparity_.reset(new std::uint16_t[pixels]());
  m->points_.reset(new MapPoint[pixels]);
  m->capacity_ = pixels;
  const BrickCapacity capacity = capacity_for_bytes(params.pool_bytes);
  const std::uint64_t need = bricks_for_one_scan(params.occupancy.resolution, params.max_range_m);
  if (capacity.bricks < need) {
    *error = "a memory of " + std::to_string(params.pool_bytes >> 20) + " MiB holds " +
             std::to_string(capacity.bricks) + " bricks, and one keyframe at resolution " +
             std::to_string(params.occupancy.resolution) + " m and max_range " + std::to_string(params.max_range_m) +
             " m may need " + std::to_string(need) + ": raise the memory, the resolution or lower max_range";
    return nullptr;
  }
  try {
    m->map_ = std::make_unique<OccupancyMap>(params.occupancy, capacity);
  } catch (const std::exception& e) {
    *error = e.what();
    return nullptr;
  }
  return m;
}

KeyframePoints KeyframeMapper::points_of(const vision::GreyView& left, const vision::GreyView& right,
                                         const geometry::RigidTransform& map_T_camera) noexcept {
  KeyframePoints out;
  count_ = 0;
  const vision::DisparityImage image{disparity_.get(), disparity_width_, disparity_height_, disparity_width_};
  if (left.width > width_ || left.height > height_ ||
      matcher_->compute(left, right, image) != vision::DisparityStatus::kOk) {
    return out;
  }
  out.textureless = texture_->apply(left, params_.disparity.downscale, image);
  out.counts = disparity_points(image, params_.disparity.downscale, camera_, map_T_camera, points_.get(), capacity_);
  count_ = out.counts.points;
  const Eigen::Vector3d& o = map_T_camera.translation;
  origin_ = {static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z())};
  out.ok = true;
  return out;
}

ScanResult KeyframeMapper::insert() noexcept {
  const ScanResult r = map_->insert_scan(points_.get(), count_, origin_, params_.max_range_m);
  count_ = 0;
  return r;
}

}  // namespace rtfuse::mapping
