#pragma once
// rtfuse-plan's start and goal pairs: one "sx sy gx gy" a line, cells of the
// map as nav_msgs/OccupancyGrid indexes them (x to the right, y up from the
// PGM's bottom row), comments and blank lines as number_rows.hpp reads them.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace rtfuse::apps {

struct PlanPair {
  int sx = 0, sy = 0, gx = 0, gy = 0;
  std::size_t line = 0;  // in the file, for the report
};

// Throws std::runtime_error("NAME:LINE: what is wrong").
std::vector<PlanPair> parse_plan_pairs(std::string_view text, const std::string& name);

// Reads and parses a file; errors name the path (and errno's text).
std::vector<PlanPair> read_plan_pairs(const std::string& path);

}  // namespace rtfuse::apps
