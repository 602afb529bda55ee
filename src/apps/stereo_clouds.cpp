#include "apps/stereo_clouds.hpp"

#include <chrono>
#include <memory>

#include "apps/grey_png.hpp"
#include "vision/semi_global_matcher.hpp"
#include "vision/texture_filter.hpp"

namespace rtfuse::apps {

bool stereo_clouds(const KittiSequence& seq, const std::vector<Eigen::Matrix4d>& poses, const std::vector<int>& frames,
                   const vision::DisparityParams& params, std::vector<StereoCloud>* out, std::string* error) {
  out->clear();
  std::unique_ptr<vision::SemiGlobalMatcher> matcher;
  std::unique_ptr<vision::TextureFilter> texture;
  GreyPng left, right;
  std::vector<std::uint16_t> disparity;
  for (const int k : frames) {
    if (k < 0 || static_cast<std::size_t>(k) >= seq.left.size() || static_cast<std::size_t>(k) >= poses.size()) {
      *error = seq.dir + ": frame " + std::to_string(k) + " has no pair or no pose";
      return false;
    }
    if (!read_luma_png(seq.left[k], &left, error) || !read_luma_png(seq.right[k], &right, error)) return false;
    if (left.width != right.width || left.height != right.height) {
      *error = seq.right[k] + ": not the size of " + seq.left[k];
      return false;
    }
    if (!matcher) {
      matcher = std::make_unique<vision::SemiGlobalMatcher>(left.width, left.height, params);
      if (!matcher->valid()) {
        *error = std::string("disparity: ") + matcher->error();
        return false;
      }
      texture = std::make_unique<vision::TextureFilter>(left.width, left.height);
    }
    const int w = matcher->output_width(left.width), h = matcher->output_height(left.height);
    disparity.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0);
    const vision::DisparityImage image{disparity.data(), w, h, w};
    const auto t0 = std::chrono::steady_clock::now();
    const vision::DisparityStatus status = matcher->compute({left.pixels.data(), left.width, left.height, left.width},
                                                            {right.pixels.data(), right.width, right.height,
                                                             right.width},
                                                            image);
    if (status != vision::DisparityStatus::kOk) {
      *error = seq.left[k] + ": disparity: " + vision::to_string(status);
      return false;
    }
    // Blank regions (sky, plain walls) matched by guesswork would put
    // phantom obstacles in the map.
    texture->apply({left.pixels.data(), left.width, left.height, left.width}, params.downscale, image);
    const auto t1 = std::chrono::steady_clock::now();
    StereoCloud cloud;
    cloud.frame = k;
    cloud.disparity_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    geometry::RigidTransform pose;
    pose.rotation = Eigen::Quaterniond(poses[k].topLeftCorner<3, 3>()).normalized();
    pose.translation = poses[k].topRightCorner<3, 1>();
    cloud.origin = {static_cast<float>(pose.translation.x()), static_cast<float>(pose.translation.y()),
                    static_cast<float>(pose.translation.z())};
    cloud.points.resize(disparity.size());
    cloud.counts = mapping::disparity_points(image, params.downscale, seq.camera, pose, cloud.points.data(),
                                             cloud.points.size());
    cloud.points.resize(cloud.counts.points);
    out->push_back(std::move(cloud));
  }
  return true;
}

}  // namespace rtfuse::apps
