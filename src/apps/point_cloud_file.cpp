#include "apps/point_cloud_file.hpp"

#include "apps/number_rows.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rtfuse::apps {

std::vector<mapping::MapPoint> parse_xyz_cloud(std::string_view text, const std::string& name) {
  std::vector<mapping::MapPoint> points;
  parse_number_rows<float, 3>(text, name, "x y z",
                              [&](const float (&v)[3], std::size_t) { points.push_back({v[0], v[1], v[2]}); });
  return points;
}

std::vector<mapping::MapPoint> read_xyz_cloud(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path + ": read failed: " + std::strerror(errno));
  return parse_xyz_cloud(text.str(), path);
}

}  // namespace rtfuse::apps
