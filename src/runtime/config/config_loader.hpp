#pragma once
// TOML -> RuntimeConfig, validated completely before anything starts.
// Schema (keys, defaults, ranges, error format): docs/configuration.md.
//
// Configuration time only: this allocates freely and must never be called
// after start().
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/config/config.hpp"

namespace rtfuse {

struct ConfigError {
  std::string file;
  int line = 0;      // 1-based; 0 when the error has no position (unreadable file)
  int column = 0;
  std::string key;   // full key, e.g. "sensor[1].config"; empty for TOML syntax errors
  std::string message;

  // "file:line:col: key: message"; the position and key parts are left out
  // when absent so a message never carries a meaningless "0:0".
  std::string to_string() const;
};

struct ConfigLoadResult {
  std::optional<RuntimeConfig> config;  // set iff errors is empty
  std::vector<ConfigError> errors;      // every problem found, in file order

  bool ok() const { return config.has_value(); }
};

ConfigLoadResult load_config_file(const std::string& path);
// The whole file as text (a config to keep in a recording); false with the
// errno in *err.
bool read_text_file(const std::string& path, std::string* text, int* err);
// source_name stands in for the file name in errors and RuntimeConfig::source.
ConfigLoadResult load_config_string(std::string_view toml_text, const std::string& source_name);

}  // namespace rtfuse
