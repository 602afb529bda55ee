#include "apps/nice_ticks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rtfuse::apps {

double nice_step_at_least(double least) {
  if (!(least > 0.0) || !std::isfinite(least)) return 1.0;
  const double decade = std::pow(10.0, std::floor(std::log10(least)));
  // A hair of slack so that least = 0.2 (not exactly representable) gives 0.2.
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * decade >= least * (1.0 - 1e-12)) return m * decade;
  return 10.0 * decade;
}

double nice_step(double span, int max_intervals) {
  return nice_step_at_least(std::abs(span) / std::max(1, max_intervals));
}

double next_nice_step(double step) {
  if (!(step > 0.0) || !std::isfinite(step)) return 1.0;
  return nice_step_at_least(step * 1.5);  // 1 -> 2, 2 -> 5 (3 rounds up), 5 -> 10
}

std::vector<double> tick_values(double lo, double hi, double step) {
  std::vector<double> ticks;
  if (!(step > 0.0) || !std::isfinite(step) || !std::isfinite(lo) || !std::isfinite(hi) || hi < lo) return ticks;
  const double slack = 1e-9 * step;
  const double first = std::ceil((lo - slack) / step), last = std::floor((hi + slack) / step);
  if (!(last - first < 1000.0)) return ticks;
  for (double k = first; k <= last; k += 1.0) ticks.push_back(k * step);
  return ticks;
}

std::string tick_label(double value, double step) {
  int decimals = 0;
  if (step > 0.0 && std::isfinite(step))
    decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 12);
  if (std::abs(value) < 0.5 * std::pow(10.0, -decimals)) value = 0.0;  // no "-0"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

}  // namespace rtfuse::apps
