// The TOML configuration, every section at once: the TOML pre-scan
// (toml_guard), toml++ itself, and each section's reader and checks.
// Property: a text is either a configuration or at least one error with a
// message, never both, never an abort.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "runtime/config/config_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const rtfuse::ConfigLoadResult r = rtfuse::load_config_string(text, "fuzz.toml");
  FUZZ_CHECK(r.ok() == r.errors.empty(), "a configuration comes with no error, an error without one");
  for (const rtfuse::ConfigError& e : r.errors) {
    FUZZ_CHECK(!e.message.empty(), "every error says what is wrong");
    FUZZ_CHECK(e.line >= 0 && e.column >= 0, "positions are 1-based or absent");
    (void)e.to_string();
  }
  return 0;
}
