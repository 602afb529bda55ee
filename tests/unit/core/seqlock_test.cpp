#include "core/seqlock.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <thread>
#include <vector>

namespace rtfuse::test {
std::uint64_t allocation_count() noexcept;
}

namespace seqlock_test {

using rtfuse::SeqLock;

struct Pose {
  double x, y, yaw;
  std::int64_t stamp;
};

TEST(CoreSeqLock, StartsZeroedAtVersionZero) {
  SeqLock<Pose> cell;
  EXPECT_EQ(cell.version(), 0U);
  Pose p{1, 2, 3, 4};
  ASSERT_TRUE(cell.try_load(p));
  EXPECT_EQ(p.x, 0.0);
  EXPECT_EQ(p.y, 0.0);
  EXPECT_EQ(p.yaw, 0.0);
  EXPECT_EQ(p.stamp, 0);
}

TEST(CoreSeqLock, StoreThenLoadSameThread) {
  SeqLock<Pose> cell;
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
TEST(CoreSeqLock, PartialLastWord) {
  struct Odd {
    char c[13];
  };
  static_assert(sizeof(Odd) == 13);
  SeqLock<Odd> cell;
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

TEST(CoreSeqLock, StoreAndLoadDoNotAllocate) {
  struct Big {
    double m[15 * 15];
  };
  SeqLock<Big> cell;
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

TEST(CoreSeqLock, ConcurrentReadersNeverSeeTornValues) {
  constexpr std::uint64_t kWrites = 100'000;
  constexpr int kReaders = 2;
  SeqLock<Stamped> cell;
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

}  // namespace seqlock_test
