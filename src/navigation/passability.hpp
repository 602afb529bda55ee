#pragma once
// Which cells of a cost grid a robot's centre may be in: the planner's graph
// and the path smoother's segments both keep to these cells.
//
// A cell is passable when its cost is below lethal_from, except unknown
// (255), which is passable exactly when unknown_passable says so. The
// default, 253, keeps the centre out of the inscribed zone (costmap_2d's
// INSCRIBED_INFLATED_OBSTACLE: a centre there means the footprint touches
// an obstacle); 254 lets it in, for a robot whose costmap inscribes
// nothing. Lethal (254) is never passable.
#include <cstdint>

#include "navigation/cost_values.hpp"

namespace rtfuse::navigation {

struct Passability {
  std::uint8_t lethal_from = kCostInscribed;  // 1..254: costs from here on are obstacles
  bool unknown_passable = false;              // 255: free space (cost 0) or an obstacle

  bool valid() const noexcept { return lethal_from >= 1 && lethal_from <= kCostLethal; }
  bool passable(std::uint8_t cost) const noexcept {
    return cost == kCostUnknown ? unknown_passable : cost < lethal_from;
  }
};

}  // namespace rtfuse::navigation
