#include "runtime/devices/mapper/mapping_config.hpp"

#include <string>

#include "mapping/keyframe_mapper.hpp"
#include "mapping/occupancy_params.hpp"
#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

void read_mapping(const Section& s, MappingSection& m) {
  s.reject_unknown({"keyframe_interval", "keyframe_distance", "keyframe_angle", "pose_delay", "disparities",
                    "half_resolution", "min_texture", "resolution", "max_range", "prob_hit", "prob_miss",
                    "clamp_min", "clamp_max", "occupancy_threshold", "memory_mb", "grid_rate", "grid_size",
                    "grid_min_z", "grid_max_z", "grid_channel", "output"});
  m.enabled = true;
  read_number(s, "keyframe_interval", m.keyframe_interval_s, non_negative_finite, "must be >= 0 s and finite");
  read_number(s, "keyframe_distance", m.keyframe_distance_m, non_negative_finite, "must be >= 0 m and finite");
  read_number(s, "keyframe_angle", m.keyframe_angle_rad, non_negative_finite, "must be >= 0 rad and finite");
  read_number(s, "pose_delay", m.pose_delay_s, [](double v) { return v >= 0 && v <= 2.0; },
              "must be between 0 and 2 s (the loop's pose history)");
  read_int(s, "disparities", m.disparities, 16, 1024);
  s.read("half_resolution", m.half_resolution);
  read_int(s, "min_texture", m.min_texture, 0, 255);
  read_number(s, "resolution", m.resolution_m, [](double v) { return v >= 0.005 && v <= 2.0; },
              "must be between 0.005 and 2 m");
  read_number(s, "max_range", m.max_range_m, [](double v) { return v > 0 && v <= 100.0; },
              "must be > 0 and <= 100 m");
  read_number(s, "prob_hit", m.prob_hit, [](double v) { return v > 0.5 && v < 1.0; }, "must be in (0.5, 1)");
  read_number(s, "prob_miss", m.prob_miss, [](double v) { return v > 0.0 && v < 0.5; }, "must be in (0, 0.5)");
  read_number(s, "clamp_min", m.clamp_min, [](double v) { return v > 0.0 && v < 1.0; }, "must be in (0, 1)");
  read_number(s, "clamp_max", m.clamp_max, [](double v) { return v > 0.0 && v < 1.0; }, "must be in (0, 1)");
  read_number(s, "occupancy_threshold", m.occupancy_threshold, [](double v) { return v > 0.0 && v < 1.0; },
              "must be in (0, 1)");
  read_int(s, "memory_mb", m.memory_mb, 1, 16384);
  read_number(s, "grid_rate", m.grid_rate_hz, non_negative_finite, "must be >= 0 Hz and finite (0: no grid)");
  read_number(s, "grid_size", m.grid_size_m, [](double v) { return v > 0 && v <= 1000.0; },
              "must be > 0 and <= 1000 m");
  read_number(s, "grid_min_z", m.grid_min_z_m, [](double v) { return std::isfinite(v); }, "must be finite");
  read_number(s, "grid_max_z", m.grid_max_z_m, [](double v) { return std::isfinite(v); }, "must be finite");
  s.read_name("grid_channel", m.grid_channel);
  s.read("output", m.output);
  if (m.grid_max_z_m <= m.grid_min_z_m) {
    s.value_error("grid_max_z", "must be above grid_min_z (" + fmt(m.grid_min_z_m) + " m), got " +
                                    fmt(m.grid_max_z_m));
  }
  if (m.disparities % (16 * (m.half_resolution ? 2 : 1)) != 0) {
    s.value_error("disparities", std::string("must be a multiple of ") + (m.half_resolution ? "32" : "16") +
                                     " (16 matched disparities a vector" +
                                     (m.half_resolution ? ", at half resolution" : "") + "), got " +
                                     std::to_string(m.disparities));
  }
  mapping::OccupancyParams p;
  p.resolution = m.resolution_m;
  p.prob_hit = m.prob_hit;
  p.prob_miss = m.prob_miss;
  p.clamp_min = m.clamp_min;
  p.clamp_max = m.clamp_max;
  p.occupancy_threshold = m.occupancy_threshold;
  const std::string bad = mapping::check(p);
  if (!bad.empty()) s.table_error("mapping", bad);
  const double cells = m.grid_size_m / m.resolution_m;
  if (cells * cells > double(1 << 24)) {
    s.value_error("grid_size", "a grid of " + fmt(m.grid_size_m) + " m at " + fmt(m.resolution_m) + " m is " +
                                   fmt(cells * cells) + " cells, more than the 16777216 one message holds");
  }
}

}  // namespace

void read_mapping_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* t = section_table(root, "mapping");
  if (!t) return;
  Diagnostics& d = root.diag();
  read_mapping(Section(t, "mapping", d), cfg.hardware.mapping);
  if (!section_table(root, "camera")) {
    Section(t, "mapping", d).table_error("mapping", "needs a [camera] section: the map is built from its frames");
  }
}

}  // namespace rtfuse::config
