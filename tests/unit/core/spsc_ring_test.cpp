#include "core/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace rtfuse::test {
std::uint64_t allocation_count() noexcept;
}

namespace spsc_ring_test {

using rtfuse::SpscRing;

TEST(CoreSpscRing, StartsEmpty) {
  SpscRing<int> ring(4);
  EXPECT_EQ(ring.capacity(), 4U);
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.peek(), nullptr);
  int out = 42;
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(out, 42);
}

TEST(CoreSpscRing, FullRejectsWithoutOverwriting) {
  SpscRing<int> ring(3);
  EXPECT_TRUE(ring.try_push(1));
  EXPECT_TRUE(ring.try_push(2));
  EXPECT_TRUE(ring.try_push(3));
  EXPECT_EQ(ring.size(), 3U);
  EXPECT_FALSE(ring.try_push(4));
  EXPECT_FALSE(ring.try_push(5));
  EXPECT_EQ(ring.size(), 3U);
  int out = 0;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 1);
  EXPECT_TRUE(ring.try_push(6));  // one slot freed, one accepted
  EXPECT_FALSE(ring.try_push(7));
  for (int expected : {2, 3, 6}) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, expected);
  }
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_TRUE(ring.empty());
}

TEST(CoreSpscRing, CapacityOne) {
  SpscRing<int> ring(1);
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(ring.try_push(i));
    ASSERT_FALSE(ring.try_push(-1));
    int out = -2;
    ASSERT_TRUE(ring.try_pop(out));
    ASSERT_EQ(out, i);
    ASSERT_FALSE(ring.try_pop(out));
  }
}

TEST(CoreSpscRing, PeekThenPop) {
  SpscRing<int> ring(2);
  ASSERT_TRUE(ring.try_push(10));
  ASSERT_TRUE(ring.try_push(20));
  const int* front = ring.peek();
  ASSERT_NE(front, nullptr);
  EXPECT_EQ(*front, 10);
  EXPECT_EQ(ring.peek(), front);  // peeking does not consume
  EXPECT_EQ(ring.size(), 2U);
  ring.pop();
  ASSERT_NE(ring.peek(), nullptr);
  EXPECT_EQ(*ring.peek(), 20);
  ring.pop();
  EXPECT_EQ(ring.peek(), nullptr);
  EXPECT_TRUE(ring.empty());
}

// Random pushes and pops against a counting model: the indices cross the
// wrap point at every offset and at every fill level, many times over.
TEST(CoreSpscRing, WrapsAroundOverManyCycles) {
  constexpr std::size_t kCapacity = 5;  // not a power of two on purpose
  SpscRing<std::uint64_t> ring(kCapacity);
  std::uint64_t next_in = 0;
  std::uint64_t next_out = 0;
  std::uint32_t lcg = 12345;
  for (int step = 0; step < 200000; ++step) {
    lcg = lcg * 1664525U + 1013904223U;
    const std::size_t queued = static_cast<std::size_t>(next_in - next_out);
    if ((lcg >> 16) % 2 == 0) {
      const bool pushed = ring.try_push(next_in);
      ASSERT_EQ(pushed, queued < kCapacity) << "step " << step;
      if (pushed) ++next_in;
    } else {
      std::uint64_t out = ~0ULL;
      const bool popped = ring.try_pop(out);
      ASSERT_EQ(popped, queued > 0) << "step " << step;
      if (popped) {
        ASSERT_EQ(out, next_out) << "step " << step;
        ++next_out;
      }
    }
    ASSERT_EQ(ring.size(), static_cast<std::size_t>(next_in - next_out));
  }
  // Tens of thousands of items through 6 slots: every slot reused thousands of times.
  EXPECT_GT(next_out, 50000U);
}

// The real queues carry measurements with fixed-size, sometimes over-aligned
// members (Eigen types: covered by the geometry tests, as core has no Eigen).
struct alignas(64) Measurement {
  std::uint64_t seq = 0;
  double covariance[15 * 15] = {};
};

TEST(CoreSpscRing, OverAlignedPayloadWithoutAllocation) {
  SpscRing<Measurement> ring(7);
  Measurement m;
  Measurement out;
  const std::uint64_t before = rtfuse::test::allocation_count();
  bool all_ok = true;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    m.seq = i;
    m.covariance[224] = static_cast<double>(i);
    all_ok &= ring.try_push(m);
    const Measurement* front = ring.peek();
    all_ok &= front != nullptr && reinterpret_cast<std::uintptr_t>(front) % alignof(Measurement) == 0;
    all_ok &= ring.try_pop(out);
    all_ok &= out.seq == i && out.covariance[224] == static_cast<double>(i);
  }
  const std::uint64_t after = rtfuse::test::allocation_count();
  EXPECT_TRUE(all_ok);
  EXPECT_EQ(after, before) << "push/peek/pop allocated";
}

TEST(CoreSpscRing, TwoThreadsKeepOrderAndLoseNothing) {
  constexpr std::uint64_t kCount = 1'000'000;
  SpscRing<std::uint64_t> ring(64);
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kCount; ++i) {
      while (!ring.try_push(i)) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t mismatches = 0;
  while (expected < kCount) {
    std::uint64_t v = 0;
    if (!ring.try_pop(v)) {
      std::this_thread::yield();
      continue;
    }
    mismatches += (v != expected);
    expected = v + 1;  // resynchronise so one error is reported once
  }
  producer.join();
  EXPECT_EQ(mismatches, 0U);
  EXPECT_EQ(expected, kCount);
  EXPECT_TRUE(ring.empty());
}

// A tiny ring keeps both threads on the full/empty edges, and a multi-word
// payload shows a slot is never read while it is being written.
TEST(CoreSpscRing, TwoThreadsPeekPopMultiWordPayload) {
  struct Item {
    std::uint64_t seq = 0;
    std::uint64_t words[7] = {};
  };
  constexpr std::uint64_t kCount = 200'000;
  SpscRing<Item> ring(2);
  std::thread producer([&] {
    Item item;
    for (std::uint64_t i = 0; i < kCount; ++i) {
      item.seq = i;
      for (std::uint64_t& w : item.words) w = i * 2654435761U;
      while (!ring.try_push(item)) std::this_thread::yield();
    }
  });
  std::uint64_t bad = 0;
  for (std::uint64_t expected = 0; expected < kCount;) {
    const Item* front = ring.peek();
    if (front == nullptr) {
      std::this_thread::yield();
      continue;
    }
    bad += front->seq != expected;
    for (std::uint64_t w : front->words) bad += w != expected * 2654435761U;
    ring.pop();
    ++expected;
  }
  producer.join();
  EXPECT_EQ(bad, 0U);
}

}  // namespace spsc_ring_test
