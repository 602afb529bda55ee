#pragma once
// Text files of rows of numbers, one row a line (a point cloud's "x y z",
// rtfuse-plan's "sx sy gx gy"): blank lines and lines starting with '#' are
// skipped; anything else that is not exactly the row's numbers, finite and
// in the type's range, is an error naming the file and line.
#include <charconv>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

namespace rtfuse::apps {

namespace detail {

inline bool row_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

[[noreturn]] inline void row_error(const std::string& name, std::size_t line, const std::string& what) {
  throw std::runtime_error(name + ":" + std::to_string(line) + ": " + what);
}

}  // namespace detail

// Calls row(const T (&values)[N], std::size_t line) for each row; `shape`
// names the numbers for the error ("x y z"). Throws std::runtime_error
// ("NAME:LINE: what is wrong").
template <class T, int N, class Row>
void parse_number_rows(std::string_view text, const std::string& name, const char* shape, Row&& row) {
  std::size_t line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    ++line;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const char* p = text.data() + pos;
    const char* const stop = text.data() + end;
    pos = end + 1;
    while (p < stop && detail::row_space(*p)) ++p;
    if (p == stop || *p == '#') continue;
    T v[N];
    for (int i = 0; i < N; ++i) {
      while (p < stop && detail::row_space(*p)) ++p;
      if (p == stop) {
        detail::row_error(name, line, "expected " + std::to_string(N) + " numbers \"" + shape + "\", found " +
                                          std::to_string(i));
      }
      if (*p == '+') ++p;  // from_chars takes no plus sign; printf's %+f writes one
      const auto r = std::from_chars(p, stop, v[i]);
      if (r.ec == std::errc::result_out_of_range) detail::row_error(name, line, "number out of range");
      if (r.ec != std::errc() || (r.ptr < stop && !detail::row_space(*r.ptr))) {
        const char* q = p;
        while (q < stop && !detail::row_space(*q)) ++q;
        detail::row_error(name, line, "\"" + std::string(p, q) + "\" is not a number");
      }
      if constexpr (std::is_floating_point_v<T>) {
        if (!std::isfinite(v[i])) detail::row_error(name, line, "number is not finite");
      }
      p = r.ptr;
    }
    while (p < stop && detail::row_space(*p)) ++p;
    if (p != stop) detail::row_error(name, line, "more than " + std::to_string(N) + " numbers on the line");
    row(v, line);
  }
}

}  // namespace rtfuse::apps
