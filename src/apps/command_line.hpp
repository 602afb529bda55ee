#pragma once
// A program's command line: options bound to variables, checks, --help,
// usage errors. Every program in src/apps parses its arguments with it.
//
// It is CLI11 behind a class that holds no CLI11 type in its interface.
// Debian 12's CLI11 (libcli11-dev 2.1) is header-only, without the compiled
// mode of later releases, and a translation unit that uses it spends some
// 18 s of -O2 compiling CLI11's inline code: nine programs paid it nine
// times in each of CI's four build trees. Behind this class it is compiled
// once per tree (command_line.cpp).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace rtfuse::apps {

class CommandLine {
 public:
  // One option, for its checks; a handle into its CommandLine, valid while
  // that lives.
  class Option {
   public:
    Option& required();
    // Giving both this and `other` is a usage error (both ways).
    Option& excludes(Option other);
    // The value must parse as a number in [lo, hi].
    Option& range(double lo, double hi);
    // The value must be a finite number >= 0.
    Option& non_negative();
    // The value must be one of `choices`, spelled exactly.
    Option& one_of(std::vector<std::string> choices);
    // --help shows the variable's value at the time of this call.
    Option& show_default();

   private:
    friend class CommandLine;
    explicit Option(CLI::Option* option) : option_(option) {}
    CLI::Option* option_;
  };

  explicit CommandLine(const std::string& description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  // `names` as CLI11 spells them: "-c,--config", or "left" for a positional.
  Option option(const std::string& names, std::string* value, const std::string& help);
  Option option(const std::string& names, double* value, const std::string& help);
  Option option(const std::string& names, int* value, const std::string& help);
  Option option(const std::string& names, std::uint64_t* value, const std::string& help);
  Option option(const std::string& names, std::vector<int>* values, const std::string& help);
  Option option(const std::string& names, std::vector<std::string>* values, const std::string& help);
  Option flag(const std::string& names, bool* value, const std::string& help);
  void version_flag(const std::string& names, const std::string& text);

  // Parses argv into the bound variables. nullopt: go on; otherwise the
  // program's exit code, its message printed: 0 after --help or --version,
  // 2 for a usage error.
  std::optional<int> parse(int argc, const char* const* argv);
  // A usage error found after parse (say, none of several alternatives
  // given): printed as parse prints one, with the hint to --help; returns 2.
  int usage_error(const std::string& message);

 private:
  std::unique_ptr<CLI::App> app_;
};

}  // namespace rtfuse::apps
