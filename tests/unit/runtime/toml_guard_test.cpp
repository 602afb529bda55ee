// runtime/toml_guard and runtime/toml.hpp: the input that Debian's toml++
// 3.3.0 aborts on never reaches it, the whitespace table it misreads is
// mended, and valid TOML passes untouched (issue 11, defect 6). The test build keeps assertions on, so a header
// that slipped through would abort this test.
#include "runtime/config/toml_guard.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "runtime/config/config_loader.hpp"
#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace toml_guard_test {

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

TEST(TomlUnicode, TheWhitespaceTableAnswersForEveryCharacter) {
  // runtime/toml.hpp mends toml++ 3.3.0's table, whose gaps (U+00A1..U+0499,
  // U+2C5E..U+3057, U+FB26..U+FEFE) fell through to __builtin_unreachable.
  // The mended function must answer as the table means to: yes for the
  // blanks it lists, no for every other code point.
  const auto blank = [](char32_t c) {
    return c == 0xA0 || c == 0x1680 || c == 0x180E || (c >= 0x2000 && c <= 0x200B) || c == 0x202F ||
           c == 0x205F || c == 0x2060 || c == 0x3000 || c == 0xFEFF;
  };
  for (char32_t c = 0x80; c <= 0x10FFFF; ++c) {
    if (c >= 0xD800 && c <= 0xDFFF) continue;
    ASSERT_EQ(toml::impl::is_non_ascii_horizontal_whitespace(c), blank(c)) << "U+" << std::hex
                                                                            << static_cast<unsigned>(c);
  }
}

TEST(TomlGuard, EveryTwoByteCharacterInEveryPlaceParsesOrIsRefused) {
  // Where toml++ tests a character for whitespace: after values, keys,
  // headers, inside arrays and tables, after a line-ending backslash. Under
  // UndefinedBehaviorSanitizer (tools/sanitize.sh asan) the unmended table
  // traps here; now each text either parses or is refused with a message.
  const std::vector<std::pair<std::string, std::string>> around = {
      {"a = 1", ""},          {"a = ", ""},           {"", " = 1"},           {"a", " = 1"},
      {"a = [1,", "]"},       {"a = {b = 1", "}"},    {"[", "]"},             {"[a", "]"},
      {"[a]", ""},            {"a = true", ""},       {"a = 1979-05-27", ""}, {"a = 'x' ", ""},
      {"a = 0x\"", "\""},     {"a = 1e\"", ".b\"!"},
      {"a = \"\"\"x\\", "\n y\"\"\""}, {"a = \"\"\"x\\\n  ", "y\"\"\""}, {"a = \"\"\"x\\  \n\n ", "\"\"\""}};
  for (char32_t c = 0x80; c < 0x800; ++c) {
    for (const auto& [before, after] : around) {
      const std::string text = before + utf8(c) + after;
      const ConfigLoadResult r = load_config_string(text, "t.toml");
      if (!r.ok()) {
        ASSERT_FALSE(r.errors.empty());
        EXPECT_FALSE(r.errors[0].message.empty()) << text;
      }
    }
  }
}

TEST(TomlGuard, TheFuzzersFirstFindingIsAnErrorNotUndefinedBehaviour) {
  // config_fuzz's first crash (tests/fuzz): a bare value running into a
  // quote, whose contents toml++ then tests for whitespace. The pre-scan
  // that tried to follow toml++ took it for a string.
  const std::string text = std::string("O=0EEE/O=0EEE/OQ.N\"") + utf8(0x12E) + ".NOQ.O\"!" + std::string(1, '\0') + "=";
  const ConfigLoadResult r = load_config_string(text, "fuzz.toml");
  EXPECT_FALSE(r.ok());
  ASSERT_FALSE(r.errors.empty());
  EXPECT_EQ(r.errors[0].file, "fuzz.toml");
}

TEST(TomlGuard, AnAssertionOfTheParserIsAnErrorOfTheFileNotAnAbort) {
  // config_fuzz's second finding: toml++ asserts that a value does not start
  // with a terminator; `]`/`}` in an array breaks that. This test build has
  // assertions on (it would abort); a release build would reach
  // __builtin_assume (undefined behaviour). runtime/toml.hpp makes it throw.
  for (const char* text : {"l=[}", "l=[}}}}}}}N \"\"z", "a = [1, }]"}) {
    const ConfigLoadResult r = load_config_string(text, "robot.toml");
    ASSERT_EQ(r.errors.size(), 1u) << text;
    EXPECT_NE(r.errors[0].message.find("internal check `!is_value_terminator(*cp)`"), std::string::npos)
        << r.errors[0].to_string();
    EXPECT_EQ(r.errors[0].to_string().rfind("robot.toml: not valid TOML", 0), 0u) << r.errors[0].to_string();
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
      // A non-ASCII character first after a line-ending backslash: refused
      // while the guard worked around toml++'s table, read since the table
      // is mended.
      "a = \"\"\"x\\\n   " + e + "y\"\"\"",
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

}  // namespace toml_guard_test
}  // namespace rtfuse::config
