#pragma once
// An error message in a fixed buffer: drivers report what failed, the value
// seen and the likely fix without std::string (nothing allocates after start).
#include <cstdarg>
#include <cstddef>
#include <cstdio>

namespace rtfuse::drivers {

class ErrorText {
 public:
  static constexpr std::size_t kCapacity = 256;

  // printf-style; truncated to kCapacity - 1 characters.
  __attribute__((format(printf, 2, 3))) void set(const char* fmt, ...) noexcept {
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf_, kCapacity, fmt, args);
    va_end(args);
  }
  void clear() noexcept { buf_[0] = '\0'; }
  bool empty() const noexcept { return buf_[0] == '\0'; }
  const char* c_str() const noexcept { return buf_; }

 private:
  char buf_[kCapacity] = {};
};

}  // namespace rtfuse::drivers
