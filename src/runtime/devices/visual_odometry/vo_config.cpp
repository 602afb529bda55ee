#include "runtime/devices/visual_odometry/vo_config.hpp"

#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

void read_vo(const Section& s, VoSection& v) {
  s.reject_unknown({"half_resolution", "ransac_iterations", "inlier_threshold", "min_inliers", "bucket_size",
                    "bucket_max", "max_interval", "max_speed", "max_turn_rate", "covariance_scale",
                    "min_linear_sigma", "min_angular_sigma"});
  v.enabled = true;
  s.read("half_resolution", v.half_resolution);
  read_int(s, "ransac_iterations", v.ransac_iterations, 10, 5000);
  read_number(s, "inlier_threshold", v.inlier_threshold_px, [](double x) { return x > 0 && x <= 20; },
              "must be > 0 and <= 20 px");
  read_int(s, "min_inliers", v.min_inliers, 6, 1000);
  read_int(s, "bucket_size", v.bucket_size_px, 8, 1000);
  read_int(s, "bucket_max", v.bucket_max, 1, 64);
  read_number(s, "max_interval", v.max_interval_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "max_speed", v.max_speed_mps, positive_finite, "must be > 0 m/s and finite");
  read_number(s, "max_turn_rate", v.max_turn_rate_rad_s, positive_finite, "must be > 0 rad/s and finite");
  read_number(s, "covariance_scale", v.covariance_scale, positive_finite, "must be > 0 and finite");
  read_number(s, "min_linear_sigma", v.min_linear_sigma_mps, non_negative_finite, "must be >= 0 m/s and finite");
  read_number(s, "min_angular_sigma", v.min_angular_sigma_rad_s, non_negative_finite,
              "must be >= 0 rad/s and finite");
}

}  // namespace

void read_vo_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* vo = section_table(root, "vo");
  if (!vo) return;
  Diagnostics& d = root.diag();
  read_vo(Section(vo, "vo", d), cfg.hardware.vo);
  if (!section_table(root, "camera")) {
    Section(vo, "vo", d).table_error("vo", "needs a [camera] section: the odometry runs on its frames");
  }
}

}  // namespace rtfuse::config
