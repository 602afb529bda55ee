#include "apps/point_cloud_file.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rtfuse::apps {

namespace {

bool space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& what) {
  throw std::runtime_error(name + ":" + std::to_string(line) + ": " + what);
}

}  // namespace

std::vector<mapping::MapPoint> parse_xyz_cloud(std::string_view text, const std::string& name) {
  std::vector<mapping::MapPoint> points;
  std::size_t line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    ++line;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const char* p = text.data() + pos;
    const char* const stop = text.data() + end;
    pos = end + 1;
    while (p < stop && space(*p)) ++p;
    if (p == stop || *p == '#') continue;
    float v[3];
    for (int i = 0; i < 3; ++i) {
      while (p < stop && space(*p)) ++p;
      if (p == stop) fail(name, line, "expected three numbers \"x y z\", found " + std::to_string(i));
      if (*p == '+') ++p;  // from_chars takes no plus sign; printf's %+f writes one
      const auto r = std::from_chars(p, stop, v[i]);
      if (r.ec == std::errc::result_out_of_range) fail(name, line, "coordinate out of float range");
      if (r.ec != std::errc() || (r.ptr < stop && !space(*r.ptr))) {
        const char* q = p;
        while (q < stop && !space(*q)) ++q;
        fail(name, line, "\"" + std::string(p, q) + "\" is not a number");
      }
      if (!std::isfinite(v[i])) fail(name, line, "coordinate is not finite");
      p = r.ptr;
    }
    while (p < stop && space(*p)) ++p;
    if (p != stop) fail(name, line, "more than three numbers on the line");
    points.push_back({v[0], v[1], v[2]});
  }
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
