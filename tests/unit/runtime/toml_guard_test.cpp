// runtime/toml_guard: the input that Debian's toml++ 3.3.0 aborts on or
// misbehaves with never reaches it, and valid TOML passes untouched
// (issue 11, defect 6). The test build keeps assertions on, so a header
// that slipped through would abort this test.
#include "runtime/toml_guard.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "runtime/config_loader.hpp"
#include "runtime/toml_reader.hpp"

namespace rtfuse::config {
namespace {

// The UTF-8 bytes of code point c (below U+10000).
std::string utf8(char32_t c) {
  std::string s;
  if (c < 0x80) {
    s += static_cast<char>(c);
  } else if (c < 0x800) {
    s += static_cast<char>(0xC0 | (c >> 6));
    s += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    s += static_cast<char>(0xE0 | (c >> 12));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    s += static_cast<char>(0x80 | (c & 0x3F));
  }
  return s;
}

bool parses(const std::string& text) {
  const std::string file = "t.toml";
  Diagnostics diag(file);
  return parse(text, file, diag).has_value();
}

TEST(TomlGuard, HeadersThatDoNotStartWithAKeyAreRefusedWhereTheyAre) {
  struct Case {
    const char* text;
    int line, column;
  };
  for (const Case& c : {Case{"[[[a]]]", 1, 3}, Case{"x = 1\n  [.a]\n", 2, 4}, Case{"[[\n", 1, 3},
                        Case{"[[ #c\n", 1, 4}, Case{"[[ [a]]]", 1, 4}, Case{"[=]", 1, 2}, Case{"[[=]]", 1, 3}}) {
    const auto h = find_toml_hazard(c.text);
    ASSERT_TRUE(h) << c.text;
    EXPECT_EQ(h->line, c.line) << c.text;
    EXPECT_EQ(h->column, c.column) << c.text;
    EXPECT_EQ(h->message, "a table header must start with a key, bare or quoted: [name] or [[name]]");
    EXPECT_FALSE(parses(c.text));
  }
}

TEST(TomlGuard, TheDaemonsConfigLoaderSaysWhereAndDoesNotAbort) {
  const ConfigLoadResult r = load_config_string("[loop]\nrate_hz = 200\n[[[sensor]]]\n", "robot.toml");
  EXPECT_FALSE(r.config);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].to_string(),
            "robot.toml:3:3: a table header must start with a key, bare or quoted: [name] or [[name]]");
  const ConfigLoadResult u = load_config_string("[loop]\nrate_hz = 200" + utf8(0xE9) + "\n", "robot.toml");
  ASSERT_EQ(u.errors.size(), 1u);
  EXPECT_EQ(u.errors[0].to_string(),
            "robot.toml:2:14: a non-ASCII character outside a string or comment (TOML allows them only there)");
}

TEST(TomlGuard, EveryTwoByteCharacterWhereToml3WouldTestItForWhitespace) {
  // U+00A1..U+0499 reach code marked unreachable in toml++ 3.3.0's
  // whitespace test; every position where it makes that test is refused,
  // for every character of two UTF-8 bytes.
  const std::vector<std::pair<std::string, std::string>> around = {
      {"a = 1", ""},          {"a = ", ""},           {"", " = 1"},           {"a", " = 1"},
      {"a = [1,", "]"},       {"a = {b = 1", "}"},    {"[", "]"},             {"[a", "]"},
      {"[a]", ""},            {"a = true", ""},       {"a = 1979-05-27", ""}, {"a = 'x' ", ""},
      {"a = \"\"\"x\\", "\n y\"\"\""}, {"a = \"\"\"x\\\n  ", "y\"\"\""}, {"a = \"\"\"x\\  \n\n ", "\"\"\""}};
  for (char32_t c = 0x80; c < 0x800; ++c) {
    for (const auto& [before, after] : around) {
      const std::string text = before + utf8(c) + after;
      EXPECT_TRUE(find_toml_hazard(text)) << before << "|U+" << std::hex << static_cast<unsigned>(c) << "|" << after;
    }
  }
}

TEST(TomlGuard, ValidTomlPassesUntouched) {
  const std::string e = utf8(0xE9), yen = utf8(0xA5), han = utf8(0x6C34);
  const std::vector<std::string> valid = {
      "a = \"caf" + e + "\"",
      "a = 'caf" + e + "'",
      "# r" + e + "sum" + e + "\na = 1",
      "a = 1 # " + yen,
      "\"" + han + "\" = 1",
      "[\"" + e + "\"]\nb = 1",
      "[[ 'x y' ]]\nb = 1",
      "a = \"\"\"\n" + e + "\"\"\"",
      "a = '''\n" + yen + "'''",
      "a = \"\"\"x\\\n   y" + e + "\"\"\"",
      "a = \"\"\"quote \\\" here\"\"\"\nb = 1",
      "a = \"\"\"ends in quotes\"\"\"\"\"\nb = [1]",
      "a = [\n  [[1]],\n  [2],\n]\n[t]\nb = { c = [1, 2] }",
      "a = \"esc \\\"[[[\"\n[[arr]]\nx = 1",
      "\xEF\xBB\xBF" "a = 1",
  };
  for (const std::string& text : valid) {
    EXPECT_FALSE(find_toml_hazard(text)) << text;
    EXPECT_TRUE(parses(text)) << text;
  }
}

}  // namespace
}  // namespace rtfuse::config
