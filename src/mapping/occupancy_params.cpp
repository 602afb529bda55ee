#include "mapping/occupancy_params.hpp"

#include <cmath>
#include <cstdio>

namespace rtfuse::mapping {

float logit(double probability) noexcept {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

LogOdds log_odds_of(const OccupancyParams& p) noexcept {
  return LogOdds{logit(p.prob_hit), logit(p.prob_miss), logit(p.clamp_min), logit(p.clamp_max),
                 logit(p.occupancy_threshold)};
}

namespace {

std::string outside(const char* name, double value, const char* range) {
  char text[160];
  std::snprintf(text, sizeof text, "%s %g must be in %s", name, value, range);
  return text;
}

bool open_unit(double v) { return v > 0.0 && v < 1.0; }

}  // namespace

std::string check(const OccupancyParams& p) {
  // 1 mm to 10 m: finer voxels make a 65536-voxel-wide map smaller than a
  // room; coarser ones are no longer an occupancy map of a robot's world.
  if (!(p.resolution >= 0.001 && p.resolution <= 10.0)) return outside("resolution", p.resolution, "[0.001, 10] m");
  if (!(p.prob_hit > 0.5 && p.prob_hit < 1.0)) return outside("prob_hit", p.prob_hit, "(0.5, 1)");
  if (!(p.prob_miss > 0.0 && p.prob_miss < 0.5)) return outside("prob_miss", p.prob_miss, "(0, 0.5)");
  if (!open_unit(p.occupancy_threshold)) return outside("occupancy_threshold", p.occupancy_threshold, "(0, 1)");
  if (!(open_unit(p.clamp_min) && p.clamp_min < p.occupancy_threshold)) {
    return outside("clamp_min", p.clamp_min, "(0, occupancy_threshold)");
  }
  if (!(open_unit(p.clamp_max) && p.clamp_max > p.occupancy_threshold)) {
    return outside("clamp_max", p.clamp_max, "(occupancy_threshold, 1)");
  }
  return {};
}

}  // namespace rtfuse::mapping
