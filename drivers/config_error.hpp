#pragma once
// The one way driver configs report a bad value at configuration time:
// "<driver>: <message>" into *error, and false, so a validator reads as a
// chain of `if (bad) return config_fail(...)`.
#include <string>

namespace rtfuse::drivers {

bool config_fail(std::string* error, const char* driver, const char* fmt, ...) __attribute__((format(printf, 3, 4)));

}  // namespace rtfuse::drivers
