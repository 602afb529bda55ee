#pragma once
// What the TOML parser must not be given. Debian 12's toml++ 3.3.0 aborts
// (an assertion) on a table header that does not start with a key, such as
// `[[[a]]]`, `[.a]` or `[[` at the end of a line. A configuration file must
// never take the daemon down, and no newer toml++ is packaged, so the text
// is scanned first (a small TOML lexer: strings, comments, brackets) and
// such a header is refused with its line and column. The scan also refuses
// a non-ASCII character outside strings and comments (TOML allows ASCII
// only there) with a plainer message than toml++'s. toml++'s other defect,
// the gap in its whitespace table, is mended where it is included
// (runtime/toml.hpp), not here: which characters toml++ tests for
// whitespace depends on its parser's state, which no pre-scan can follow
// (the fuzzer found `a=0E"Į"` within seconds of a scan that tried).
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
