#pragma once
// What the TOML parser must not be given. Debian 12's toml++ 3.3.0 aborts
// (an assertion) on a table header that does not start with a key, such as
// `[[[a]]]`, `[.a]` or `[[` at the end of a line, and reaches code marked
// unreachable (undefined behaviour in a release build) when it tests a
// character from U+00A1 to U+0499 for whitespace, which it does outside
// strings and comments and after a line-ending backslash in a multi-line
// basic string. A configuration file must never take the daemon down, and
// no newer toml++ is packaged, so the text is scanned first (a small TOML
// lexer: strings, comments, brackets) and such input is refused with its
// line and column. Outside strings and comments TOML allows ASCII only, so
// that part refuses nothing valid; what it refuses inside a multi-line
// string (a non-ASCII character first after a line-ending backslash) the
// message says how to write instead.
#include <optional>
#include <string>
#include <string_view>

namespace rtfuse::config {

struct TomlHazard {
  int line = 0;    // 1-based
  int column = 0;  // 1-based, in bytes
  std::string message;
};

std::optional<TomlHazard> find_toml_hazard(std::string_view text);

}  // namespace rtfuse::config
