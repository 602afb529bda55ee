// MonotonicClock against the kernel's CLOCK_MONOTONIC; SimClock's exact,
// lockstep advance. No timing upper bounds beyond generous sanity checks:
// shared CI machines stall for whole scheduler quanta.
#include "hal/linux/monotonic_clock.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/time.h>

#include <atomic>
#include <cstring>

#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::hal {
namespace monotonic_clock_test {
using mock::SimClock;

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSanity = 2 * kNsPerSec;

TEST(MonotonicClock, NowIsTheKernelsMonotonicClockAndNeverGoesBack) {
  MonotonicClock clock;
  const TimeNs before = monotonic_now_ns();
  TimeNs prev = clock.now();
  EXPECT_GE(prev, before);
  for (int i = 0; i < 10'000; ++i) {
    const TimeNs t = clock.now();
    ASSERT_GE(t, prev) << i;
    prev = t;
  }
  EXPECT_LE(prev, monotonic_now_ns());
  EXPECT_LT(prev - before, kSanity);
}

TEST(MonotonicClock, SleepUntilWakesAtOrAfterTheDeadline) {
  MonotonicClock clock;
  for (int i = 0; i < 5; ++i) {
    const TimeNs deadline = clock.now() + 2 * kMs;
    clock.sleep_until(deadline);
    const TimeNs woke = clock.now();
    EXPECT_GE(woke, deadline);
    EXPECT_LT(woke - deadline, kSanity);
  }
}

TEST(MonotonicClock, PastAndNegativeDeadlinesReturnAtOnce) {
  MonotonicClock clock;
  const TimeNs start = clock.now();
  clock.sleep_until(start - 10 * kMs);
  clock.sleep_until(0);
  clock.sleep_until(-5 * kNsPerSec);
  EXPECT_LT(clock.now() - start, kSanity);
}

std::atomic<int> g_alarms{0};
void on_alarm(int) { g_alarms.fetch_add(1); }

TEST(MonotonicClock, SignalsDoNotCutTheSleepShort) {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = &on_alarm;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: clock_nanosleep returns EINTR on each signal
  struct sigaction old;
  ASSERT_EQ(sigaction(SIGALRM, &sa, &old), 0);
  itimerval every_ms{};
  every_ms.it_interval.tv_usec = 1000;
  every_ms.it_value.tv_usec = 1000;
  g_alarms = 0;
  ASSERT_EQ(setitimer(ITIMER_REAL, &every_ms, nullptr), 0);

  MonotonicClock clock;
  const TimeNs deadline = clock.now() + 30 * kMs;
  clock.sleep_until(deadline);
  const TimeNs woke = clock.now();

  itimerval off{};
  setitimer(ITIMER_REAL, &off, nullptr);
  sigaction(SIGALRM, &old, nullptr);

  EXPECT_GT(g_alarms.load(), 0) << "no signal arrived during the sleep, the test proves nothing";
  EXPECT_GE(woke, deadline);
  EXPECT_LT(woke - deadline, kSanity);
}

TEST(MonotonicClock, UsableThroughTheHalInterfaceWithoutAllocating) {
  MonotonicClock mc;
  Clock& clock = mc;
  (void)clock.now();
  std::size_t allocations = 0;
  TimeNs last = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 20; ++i) {
      clock.sleep_until(clock.now() + 100'000);
      last = clock.now();
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(last, 0);
}

TEST(SimClock, StartsAtTheGivenTime) {
  EXPECT_EQ(SimClock().now(), 0);
  EXPECT_EQ(SimClock(1'234'567).now(), 1'234'567);
}

TEST(SimClock, SleepUntilJumpsExactlyToTheDeadline) {
  SimClock clock(10 * kMs);
  clock.sleep_until(12 * kMs + 7);
  EXPECT_EQ(clock.now(), 12 * kMs + 7);
  clock.sleep_until(12 * kMs + 8);
  EXPECT_EQ(clock.now(), 12 * kMs + 8);
}

TEST(SimClock, PastDeadlineNeverMovesTimeBack) {
  SimClock clock(50 * kMs);
  clock.sleep_until(40 * kMs);
  EXPECT_EQ(clock.now(), 50 * kMs);
  clock.sleep_until(50 * kMs);
  EXPECT_EQ(clock.now(), 50 * kMs);
}

TEST(SimClock, SetAndAdvanceAreExact) {
  SimClock clock;
  clock.set(5 * kNsPerSec);
  EXPECT_EQ(clock.now(), 5 * kNsPerSec);
  clock.advance(333);
  EXPECT_EQ(clock.now(), 5 * kNsPerSec + 333);
  clock.set(kNsPerSec);  // the replayer may rewind explicitly
  EXPECT_EQ(clock.now(), kNsPerSec);
}

TEST(SimClock, FixedRateLoopRunsInLockstep) {
  SimClock sim(1'000 * kMs);
  Clock& clock = sim;
  const TimeNs period = kMs;
  TimeNs next = clock.now();
  int ticks = 0;
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 1'000; ++i) {
      next += period;
      clock.sleep_until(next);
      if (clock.now() == next) ++ticks;
    }
    allocations = scope.count();
  }
  EXPECT_EQ(ticks, 1'000);
  EXPECT_EQ(clock.now(), 2'000 * kMs);
  EXPECT_EQ(allocations, 0u);
}

}  // namespace monotonic_clock_test
}  // namespace rtfuse::hal
