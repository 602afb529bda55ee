#pragma once
// One clock in the process: CLOCK_MONOTONIC, int64 nanoseconds. LCM messages
// carry utime in microseconds, so conversions live here and nowhere else.
#include <cmath>
#include <cstdint>
#include <cerrno>
#include <ctime>

namespace rtfuse {

using TimeNs = std::int64_t;

constexpr TimeNs kNsPerSec = 1'000'000'000;
constexpr TimeNs kNsPerUs = 1'000;

inline TimeNs monotonic_now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}

// The utimes whose nanoseconds fit TimeNs: +-9.2e15 us, some 292 years
// either side of the clock's origin. Anything beyond is a corrupt or
// hostile stamp, and converting it would overflow (undefined behaviour):
// every utime from outside (messages, logs, recordings) is checked with
// utime_in_range before utime_to_ns.
constexpr std::int64_t kMaxUtime = INT64_MAX / kNsPerUs;
constexpr bool utime_in_range(std::int64_t utime) noexcept { return utime >= -kMaxUtime && utime <= kMaxUtime; }

constexpr std::int64_t ns_to_utime(TimeNs t) noexcept { return t / kNsPerUs; }
// Precondition: utime_in_range(utime).
constexpr TimeNs utime_to_ns(std::int64_t utime) noexcept { return utime * kNsPerUs; }
constexpr double ns_to_sec(TimeNs t) noexcept { return static_cast<double>(t) * 1e-9; }
inline TimeNs sec_to_ns(double s) noexcept { return static_cast<TimeNs>(std::llround(s * 1e9)); }

inline timespec ns_to_timespec(TimeNs t) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t / kNsPerSec);
  ts.tv_nsec = static_cast<long>(t % kNsPerSec);
  return ts;
}

// clock_nanosleep(TIMER_ABSTIME) until t, resuming after signals: the one
// blocking call the real-time threads make.
inline void sleep_until(TimeNs t) noexcept {
  const timespec ts = ns_to_timespec(t);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace rtfuse
