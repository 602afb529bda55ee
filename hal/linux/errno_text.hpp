#pragma once
// errno as text without allocating and without the non-thread-safe
// strerror(): usable on a backend's run-time error paths.
#include <cstring>

namespace rtfuse::hal {

struct ErrnoText {
  explicit ErrnoText(int err) noexcept { text = pick(strerror_r(err, buf, sizeof buf), buf); }
  char buf[128] = {};
  const char* text = "";

 private:
  // glibc gives the GNU flavour (returns char*) under _GNU_SOURCE, which g++
  // defines, and the XSI one (returns int) elsewhere: accept both.
  [[maybe_unused]] static const char* pick(int rc, const char* b) noexcept { return rc == 0 ? b : "unknown error"; }
  [[maybe_unused]] static const char* pick(const char* t, const char*) noexcept { return t; }
};

}  // namespace rtfuse::hal
