// The two latest-value cells, SeqLock (one copy, for a writer no reader
// can stop) and SeqLatch (two, for a writer below its readers), share
// their contract: each test below runs on both. The last two stop a writer
// mid-store, as a higher-priority reader on its CPU does.
#include <gtest/gtest.h>
#include <semaphore.h>
#include <signal.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "core/seq_cell.hpp"

namespace rtfuse::test {
std::uint64_t allocation_count() noexcept;
}

namespace seq_cell_test {

using rtfuse::SeqLatch;
using rtfuse::SeqLock;

struct Pose {
  double x, y, yaw;
  std::int64_t stamp;
};

template <template <class> class Cell>
struct CellOf {
  template <class T>
  using type = Cell<T>;
};

template <class C>
class CoreSeqCell : public ::testing::Test {};

struct CellNames {
  template <class C>
  static std::string GetName(int) {
    return std::is_same_v<C, CellOf<SeqLock>> ? "SeqLock" : "SeqLatch";
  }
};
using Cells = ::testing::Types<CellOf<SeqLock>, CellOf<SeqLatch>>;
TYPED_TEST_SUITE(CoreSeqCell, Cells, CellNames);

TYPED_TEST(CoreSeqCell, StartsZeroedAtVersionZero) {
  typename TypeParam::template type<Pose> cell;
  EXPECT_EQ(cell.version(), 0U);
  Pose p{1, 2, 3, 4};
  ASSERT_TRUE(cell.try_load(p));
  EXPECT_EQ(p.x, 0.0);
  EXPECT_EQ(p.y, 0.0);
  EXPECT_EQ(p.yaw, 0.0);
  EXPECT_EQ(p.stamp, 0);
}

TYPED_TEST(CoreSeqCell, StoreThenLoadSameThread) {
  typename TypeParam::template type<Pose> cell;
  for (int i = 1; i <= 3; ++i) {
    cell.store(Pose{1.5 * i, -2.0 * i, 0.25, 1000 + i});
    EXPECT_EQ(cell.version(), static_cast<std::uint64_t>(i));
    Pose p{};
    cell.load(p);
    EXPECT_EQ(p.x, 1.5 * i);
    EXPECT_EQ(p.y, -2.0 * i);
    EXPECT_EQ(p.yaw, 0.25);
    EXPECT_EQ(p.stamp, 1000 + i);
    Pose q{};
    ASSERT_TRUE(cell.try_load(q));
    EXPECT_EQ(std::memcmp(&p, &q, sizeof(Pose)), 0);
  }
}

// sizeof(T) not a multiple of 8: the last word is partial and must neither
// lose bytes nor write past the end of the caller's object.
TYPED_TEST(CoreSeqCell, PartialLastWord) {
  struct Odd {
    char c[13];
  };
  static_assert(sizeof(Odd) == 13);
  typename TypeParam::template type<Odd> cell;
  Odd in{};
  for (int i = 0; i < 13; ++i) in.c[i] = static_cast<char>('a' + i);
  cell.store(in);
  struct Guarded {
    Odd value;
    char guard[3];
  } out{};
  std::memset(out.guard, 0x5A, sizeof(out.guard));
  cell.load(out.value);
  EXPECT_EQ(std::memcmp(in.c, out.value.c, sizeof(in.c)), 0);
  for (char g : out.guard) EXPECT_EQ(g, 0x5A);
}

TYPED_TEST(CoreSeqCell, StoreAndLoadDoNotAllocate) {
  struct Big {
    double m[15 * 15];
  };
  typename TypeParam::template type<Big> cell;
  Big in{};
  Big out{};
  const std::uint64_t before = rtfuse::test::allocation_count();
  for (int i = 0; i < 100; ++i) {
    in.m[i] = i;
    cell.store(in);
    cell.load(out);
  }
  const std::uint64_t after = rtfuse::test::allocation_count();
  EXPECT_EQ(after, before);
  EXPECT_EQ(out.m[99], 99.0);
}

// Every word of a stored value equals the same counter, so a torn read shows
// up as two different words inside one loaded value. 2 kB, about the size of
// the filter snapshot: a long copy widens the window a torn read needs
// (with the sequence check removed, this test does catch tearing).
constexpr int kStampedWords = 256;
struct Stamped {
  std::uint64_t words[kStampedWords];
};

TYPED_TEST(CoreSeqCell, ConcurrentReadersNeverSeeTornValues) {
  constexpr std::uint64_t kWrites = 100'000;
  constexpr int kReaders = 2;
  typename TypeParam::template type<Stamped> cell;
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> total_loads{0};
  std::atomic<int> readers_ready{0};

  struct ReaderStats {
    std::uint64_t loads = 0;
    std::uint64_t torn = 0;
    std::uint64_t went_backwards = 0;
    std::uint64_t failed_try = 0;
    std::uint64_t clobbered_on_failure = 0;
  };
  std::vector<ReaderStats> stats(kReaders);

  std::vector<std::thread> readers;
  for (int r = 0; r < kReaders; ++r) {
    readers.emplace_back([&, r] {
      ReaderStats& s = stats[r];
      std::uint64_t last = 0;
      Stamped v{};
      readers_ready.fetch_add(1);
      while (!done.load(std::memory_order_acquire)) {
        // Alternate the retrying load and the single attempt.
        if (s.loads % 2 == 0) {
          cell.load(v);
        } else {
          Stamped sentinel;
          for (auto& w : sentinel.words) w = ~0ULL;
          if (!cell.try_load(sentinel)) {
            ++s.failed_try;
            for (auto w : sentinel.words) s.clobbered_on_failure += w != ~0ULL;
            continue;
          }
          v = sentinel;
        }
        ++s.loads;
        total_loads.fetch_add(1, std::memory_order_relaxed);
        for (auto w : v.words) s.torn += w != v.words[0];
        s.went_backwards += v.words[0] < last;
        last = v.words[0];
      }
    });
  }

  // Keep writing past kWrites until the readers have overlapped enough
  // stores, however the two cores happen to be scheduled.
  while (readers_ready.load() < kReaders) std::this_thread::yield();
  Stamped value{};
  std::uint64_t writes = 0;
  while (writes < kWrites ||
         (total_loads.load(std::memory_order_relaxed) < 10'000 && writes < 100 * kWrites)) {
    ++writes;
    for (auto& w : value.words) w = writes;
    cell.store(value);
  }
  done.store(true, std::memory_order_release);
  for (auto& t : readers) t.join();

  EXPECT_EQ(cell.version(), writes);
  EXPECT_GE(total_loads.load(), 10'000U);
  for (int r = 0; r < kReaders; ++r) {
    SCOPED_TRACE(r);
    EXPECT_EQ(stats[r].torn, 0U);
    EXPECT_EQ(stats[r].went_backwards, 0U);
    EXPECT_EQ(stats[r].clobbered_on_failure, 0U);
  }
  Stamped final_value{};
  cell.load(final_value);
  EXPECT_EQ(final_value.words[0], writes);
  EXPECT_EQ(final_value.words[kStampedWords - 1], writes);
}

// --- a writer stopped mid-store -------------------------------------------

// Under ThreadSanitizer a signal waits for the thread's next call into
// the runtime's interceptors, which the writer's loop never makes: the
// stop would never come.
#if defined(__SANITIZE_THREAD__)
constexpr bool kSignalsDeferred = true;
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
constexpr bool kSignalsDeferred = true;
#else
constexpr bool kSignalsDeferred = false;
#endif
#else
constexpr bool kSignalsDeferred = false;
#endif

sem_t g_stopped;
sem_t g_resume;

// Runs on the writer's thread wherever the signal caught it, and holds it
// there until the test has read.
void hold_writer(int) {
  const int saved = errno;
  sem_post(&g_stopped);
  while (sem_wait(&g_resume) != 0) {
  }
  errno = saved;
}

struct StoppedReads {
  int stops = 0;
  int failed = 0;    // try_load said the value was being written
  int torn = 0;      // a copy whose words differ
  int previous = 0;  // the value before the one the writer had started
};

// A writer storing back to back, stopped `stops` times wherever it happens
// to be, a try_load each time: what a reader above it on its CPU sees.
template <template <class> class Cell>
StoppedReads read_with_the_writer_stopped(int stops) {
  Cell<Stamped> cell;
  std::atomic<std::uint64_t> started{0};
  std::atomic<bool> done{false};
  StoppedReads r;
  EXPECT_EQ(sem_init(&g_stopped, 0, 0), 0);
  EXPECT_EQ(sem_init(&g_resume, 0, 0), 0);
  struct sigaction hold {};
  struct sigaction before {};
  hold.sa_handler = hold_writer;
  sigemptyset(&hold.sa_mask);
  EXPECT_EQ(sigaction(SIGUSR1, &hold, &before), 0);
  std::thread writer([&] {
    Stamped v{};
    for (std::uint64_t k = 1; !done.load(std::memory_order_relaxed); ++k) {
      for (auto& w : v.words) w = k;
      started.store(k, std::memory_order_relaxed);
      cell.store(v);
    }
  });
  while (started.load(std::memory_order_relaxed) == 0) std::this_thread::yield();
  for (; r.stops < stops; ++r.stops) {
    if (pthread_kill(writer.native_handle(), SIGUSR1) != 0) break;
    while (sem_wait(&g_stopped) != 0) {
    }
    const std::uint64_t k = started.load(std::memory_order_relaxed);  // sem_post/sem_wait order it
    Stamped v{};
    if (!cell.try_load(v)) {
      ++r.failed;
    } else {
      for (auto w : v.words) r.torn += w != v.words[0];
      r.previous += v.words[0] + 1 == k;
      r.torn += v.words[0] != k && v.words[0] + 1 != k;
    }
    sem_post(&g_resume);
    // Let it run on before the next stop: a signal sent at once would wait
    // for the handler to return and stop it at the same place again.
    while (started.load(std::memory_order_relaxed) < k + 2) std::this_thread::yield();
  }
  done.store(true, std::memory_order_relaxed);
  writer.join();
  sigaction(SIGUSR1, &before, nullptr);
  sem_destroy(&g_stopped);
  sem_destroy(&g_resume);
  return r;
}

// Why the devices' health does not go through a SeqLock: stopped mid-store,
// its writer leaves the sequence odd, and a reader that keeps the CPU (the
// loop above a device thread) can never read.
TEST(CoreSeqLock, AWriterStoppedMidStoreLeavesNothingToRead) {
  if (kSignalsDeferred) GTEST_SKIP() << "ThreadSanitizer defers the signal that stops the writer";
  const StoppedReads r = read_with_the_writer_stopped<SeqLock>(200);
  ASSERT_EQ(r.stops, 200);
  // A store is most of the writer's loop: most stops land inside one.
  EXPECT_GE(r.failed, 20) << "the stops did not catch the writer mid-store";
  EXPECT_EQ(r.torn, 0);
}

TEST(CoreSeqLatch, AWriterStoppedMidStoreLeavesTheWholePreviousValue) {
  if (kSignalsDeferred) GTEST_SKIP() << "ThreadSanitizer defers the signal that stops the writer";
  const StoppedReads r = read_with_the_writer_stopped<SeqLatch>(200);
  ASSERT_EQ(r.stops, 200);
  EXPECT_EQ(r.failed, 0);
  EXPECT_EQ(r.torn, 0);
  // Stopped in the first copy it reads the second, the previous value.
  EXPECT_GE(r.previous, 20) << "the stops did not catch the writer mid-store";
}

}  // namespace seq_cell_test
