#include "runtime/config/toml_guard.hpp"

#include <cstdio>

namespace rtfuse::config {
namespace {

bool bare_key_char(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

class Scanner {
 public:
  explicit Scanner(std::string_view text) : s_(text) {}

  std::optional<TomlHazard> run() {
    // A UTF-8 byte order mark, which toml++ skips.
    if (at(0) == 0xEF && at(1) == 0xBB && at(2) == 0xBF) i_ = line_begin_ = 3;
    while (i_ < s_.size()) {
      const auto c = static_cast<unsigned char>(s_[i_]);
      if (c >= 0x80) return hazard("a non-ASCII character outside a string or comment (TOML allows them only there)");
      if (c == '#') {
        skip_comment();
      } else if (c == '"' || c == '\'') {
        if (auto h = string(c)) return h;
      } else if (c == '[' && line_start_ && depth_ == 0) {
        if (auto h = table_header()) return h;
      } else {
        if (c == '[' || c == '{') ++depth_;
        if ((c == ']' || c == '}') && depth_ > 0) --depth_;
        line_start_ = c == '\n' || (line_start_ && (c == ' ' || c == '\t' || c == '\r'));
        advance();
      }
    }
    return std::nullopt;
  }

 private:
  unsigned char at(std::size_t k) const { return k < s_.size() ? static_cast<unsigned char>(s_[k]) : 0; }

  void advance() {
    if (s_[i_] == '\n') {
      ++line_;
      line_begin_ = i_ + 1;
    }
    ++i_;
  }

  TomlHazard hazard(const char* what) const {
    return TomlHazard{line_, static_cast<int>(i_ - line_begin_) + 1, what};
  }

  void skip_comment() {
    while (i_ < s_.size() && s_[i_] != '\n') advance();
  }

  // `[` or `[[` at the start of a line, outside any value: the first thing
  // after it (and blanks) must start a key, or be the `]` of an empty one.
  std::optional<TomlHazard> table_header() {
    // The rest of the header is scanned as any text, its brackets counted:
    // they balance in a well-formed header, and toml++ stops at the first
    // malformed one.
    advance();
    ++depth_;
    if (at(i_) == '[') advance(), ++depth_;
    line_start_ = false;
    while (at(i_) == ' ' || at(i_) == '\t') advance();
    const unsigned char c = at(i_);
    if (!bare_key_char(c) && c != '"' && c != '\'' && c != ']') {
      return hazard("a table header must start with a key, bare or quoted: [name] or [[name]]");
    }
    return std::nullopt;
  }

  // A string from its opening quote; after it, the scan goes on at the
  // character after the closing one.
  std::optional<TomlHazard> string(unsigned char quote) {
    line_start_ = false;
    const bool multi = at(i_ + 1) == quote && at(i_ + 2) == quote;
    for (int k = 0; k < (multi ? 3 : 1); ++k) advance();
    while (i_ < s_.size()) {
      const unsigned char c = at(i_);
      if (c == quote && (!multi || (at(i_ + 1) == quote && at(i_ + 2) == quote))) {
        // A multi-line string may end in up to five quotes (two of them
        // its own).
        int run = 0;
        while (at(i_) == quote && run < (multi ? 5 : 1)) advance(), ++run;
        return std::nullopt;
      }
      if (c == '\n' && !multi) return std::nullopt;  // toml++ reports it
      if (c == '\\' && quote == '"') {
        advance();
        // The escaped character (a quote perhaps) is skipped; a line-ending
        // backslash's newline and blanks are plain text to this scan.
        if (i_ < s_.size() && (multi || at(i_) != '\n')) advance();
        continue;
      }
      advance();
    }
    return std::nullopt;
  }

  std::string_view s_;
  std::size_t i_ = 0;
  std::size_t line_begin_ = 0;
  int line_ = 1;
  int depth_ = 0;  // open [ and { of values (and of the header being read)
  bool line_start_ = true;
};

}  // namespace

std::optional<TomlHazard> find_toml_hazard(std::string_view text) { return Scanner(text).run(); }

}  // namespace rtfuse::config
