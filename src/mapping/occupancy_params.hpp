#pragma once
// The sensor model of the occupancy map, OctoMap's defaults: a hit raises a
// voxel's log-odds by logit(0.7), a ray through it lowers them by
// logit(0.4), the value is clamped to [logit(0.1192), logit(0.971)] so a
// changed world can be re-learnt, and a voxel is occupied at 0.5 or above.
// The log-odds are float32 computed as OctoMap computes them
// ((float)log(p / (1 - p))), so the sums a voxel goes through are OctoMap's.
#include <cstddef>
#include <string>

namespace rtfuse::mapping {

struct OccupancyParams {
  double resolution = 0.05;         // m, edge of a voxel
  double prob_hit = 0.7;            // in (0.5, 1)
  double prob_miss = 0.4;           // in (0, 0.5)
  double clamp_min = 0.1192;        // probability floor, below occupancy_threshold
  double clamp_max = 0.971;         // probability ceiling, above occupancy_threshold
  double occupancy_threshold = 0.5; // occupied at or above
};

// The parameters in the form the map updates with.
struct LogOdds {
  float hit;
  float miss;
  float clamp_min;
  float clamp_max;
  float occupied;  // threshold
};

float logit(double probability) noexcept;
LogOdds log_odds_of(const OccupancyParams& params) noexcept;

// Empty when the parameters make a map; else what is wrong and the range
// that is accepted ("prob_hit 0.4 must be in (0.5, 1)").
std::string check(const OccupancyParams& params);

}  // namespace rtfuse::mapping
