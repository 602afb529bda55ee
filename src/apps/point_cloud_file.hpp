#pragma once
// Point clouds as text, one "x y z" (metres) a line: the format of OctoMap's
// own scan.dat and of most tools' xyz exports. Blank lines and lines
// starting with '#' are skipped; anything else that is not three finite
// numbers is an error naming the file and line.
#include <string>
#include <string_view>
#include <vector>

#include "mapping/map_point.hpp"

namespace rtfuse::apps {

// Throws std::runtime_error("NAME:LINE: what is wrong").
std::vector<mapping::MapPoint> parse_xyz_cloud(std::string_view text, const std::string& name);

// Reads and parses a file; errors name the path (and errno's text when it
// cannot be read).
std::vector<mapping::MapPoint> read_xyz_cloud(const std::string& path);

}  // namespace rtfuse::apps
