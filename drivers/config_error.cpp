#include "drivers/config_error.hpp"

#include <cstdarg>
#include <cstdio>

namespace rtfuse::drivers {

bool config_fail(std::string* error, const char* driver, const char* fmt, ...) {
  if (error != nullptr) {
    char buf[320];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, args);
    va_end(args);
    *error = std::string(driver) + ": " + buf;
  }
  return false;
}

}  // namespace rtfuse::drivers
