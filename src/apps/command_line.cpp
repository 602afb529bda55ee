#include "apps/command_line.hpp"

#include <cmath>
#include <cstdio>
#include <utility>

#include <CLI/CLI.hpp>

namespace rtfuse::apps {

namespace {

// Usage errors are exit 2 in every program (CLI11's own codes start at 100).
int exit_code(CLI::App& app, const CLI::Error& error) { return app.exit(error) == 0 ? 0 : 2; }

std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", v);
  return text;
}

}  // namespace

CommandLine::CommandLine(const std::string& description) : app_(std::make_unique<CLI::App>(description)) {}

CommandLine::~CommandLine() = default;

CommandLine::Option& CommandLine::Option::required() {
  option_->required();
  return *this;
}

CommandLine::Option& CommandLine::Option::excludes(Option other) {
  option_->excludes(other.option_);
  other.option_->excludes(option_);
  return *this;
}

CommandLine::Option& CommandLine::Option::range(double lo, double hi) {
  // Not CLI::Range: its message prints whole-number limits as 16777216.000000.
  const std::string limits = "[" + number_text(lo) + ", " + number_text(hi) + "]";
  option_->check(CLI::Validator(
      [lo, hi, limits](std::string& text) {
        double v = 0.0;
        if (CLI::detail::lexical_cast(text, v) && v >= lo && v <= hi) return std::string();
        return "must be a number in " + limits + ", got '" + text + "'";
      },
      limits));
  return *this;
}

CommandLine::Option& CommandLine::Option::non_negative() {
  // CLI::NonNegativeNumber takes "inf"; no option here means forever.
  option_->check(CLI::Validator(
      [](std::string& text) {
        double v = -1.0;
        if (CLI::detail::lexical_cast(text, v) && std::isfinite(v) && v >= 0.0) return std::string();
        return "must be a finite number >= 0, got '" + text + "'";
      },
      "NONNEGATIVE"));
  return *this;
}

CommandLine::Option& CommandLine::Option::one_of(std::vector<std::string> choices) {
  option_->check(CLI::IsMember(std::move(choices)));
  return *this;
}

CommandLine::Option& CommandLine::Option::show_default() {
  option_->capture_default_str();
  return *this;
}

CommandLine::Option CommandLine::option(const std::string& names, std::string* value, const std::string& help) {
  return Option(app_->add_option(names, *value, help));
}

CommandLine::Option CommandLine::option(const std::string& names, double* value, const std::string& help) {
  return Option(app_->add_option(names, *value, help));
}

CommandLine::Option CommandLine::option(const std::string& names, int* value, const std::string& help) {
  return Option(app_->add_option(names, *value, help));
}

CommandLine::Option CommandLine::option(const std::string& names, std::uint64_t* value, const std::string& help) {
  return Option(app_->add_option(names, *value, help));
}

CommandLine::Option CommandLine::option(const std::string& names, std::vector<int>* values, const std::string& help) {
  return Option(app_->add_option(names, *values, help));
}

CommandLine::Option CommandLine::option(const std::string& names, std::vector<std::string>* values,
                                        const std::string& help) {
  return Option(app_->add_option(names, *values, help));
}

CommandLine::Option CommandLine::flag(const std::string& names, bool* value, const std::string& help) {
  return Option(app_->add_flag(names, *value, help));
}

void CommandLine::version_flag(const std::string& names, const std::string& text) {
  app_->set_version_flag(names, text);
}

std::optional<int> CommandLine::parse(int argc, const char* const* argv) {
  try {
    app_->parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return exit_code(*app_, e);
  }
  return std::nullopt;
}

int CommandLine::usage_error(const std::string& message) {
  return exit_code(*app_, CLI::ValidationError(message));
}

}  // namespace rtfuse::apps
