#include "apps/plan_pairs.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "apps/number_rows.hpp"

namespace rtfuse::apps {

std::vector<PlanPair> parse_plan_pairs(std::string_view text, const std::string& name) {
  std::vector<PlanPair> pairs;
  parse_number_rows<int, 4>(text, name, "sx sy gx gy", [&](const int (&v)[4], std::size_t line) {
    pairs.push_back({v[0], v[1], v[2], v[3], line});
  });
  return pairs;
}

std::vector<PlanPair> read_plan_pairs(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path + ": read failed: " + std::strerror(errno));
  return parse_plan_pairs(text.str(), path);
}

}  // namespace rtfuse::apps
