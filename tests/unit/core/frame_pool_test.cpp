// FramePool: slots lent by handle, never overwritten while held, drops
// counted when every slot is busy, no allocation after construction, and a
// two-thread stress run in which the consumer never sees a torn frame.
#include "core/frame_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "support/alloc_counter.hpp"

namespace frame_pool_test {

using rtfuse::FramePool;

// Every byte of a frame derives from its sequence number, so a frame mixed
// from two fills (a torn frame) cannot pass check().
std::uint8_t pattern(std::uint32_t seq, int eye, int x, int y) {
  return static_cast<std::uint8_t>(seq * 31u + static_cast<std::uint32_t>(eye * 7 + x * 3 + y * 5));
}

void fill(FramePool::WriteSlot& w, std::uint32_t seq) {
  for (int y = 0; y < w.height; ++y) {
    for (int x = 0; x < w.width; ++x) {
      w.left[y * w.stride + x] = pattern(seq, 0, x, y);
      w.right[y * w.stride + x] = pattern(seq, 1, x, y);
    }
  }
}

bool check(const FramePool::Frame& f) {
  if (f.stamp != static_cast<rtfuse::TimeNs>(f.sequence) * 1000) return false;
  for (int y = 0; y < f.height; ++y) {
    for (int x = 0; x < f.width; ++x) {
      if (f.left[y * f.stride + x] != pattern(f.sequence, 0, x, y)) return false;
      if (f.right[y * f.stride + x] != pattern(f.sequence, 1, x, y)) return false;
    }
  }
  return true;
}

std::uint64_t produce(FramePool& pool, std::uint32_t seq) {
  FramePool::WriteSlot w = pool.acquire();
  if (!w.valid()) return 0;
  fill(w, seq);
  return pool.publish(w, static_cast<rtfuse::TimeNs>(seq) * 1000, seq);
}

TEST(CoreFramePool, GeometryAndAlignment) {
  FramePool pool(3, 70, 5);
  EXPECT_EQ(pool.slots(), 3);
  EXPECT_EQ(pool.width(), 70);
  EXPECT_EQ(pool.height(), 5);
  EXPECT_EQ(pool.stride(), 128);  // rows start on cache lines
  FramePool::WriteSlot w = pool.acquire();
  ASSERT_TRUE(w.valid());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(w.left) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(w.right) % 64, 0u);
  EXPECT_GE(w.right - w.left, 128 * 5);
  pool.abandon(w);
  EXPECT_EQ(pool.busy(), 0);
  EXPECT_EQ(FramePool(1, 4, 4).slots(), 2);  // fewer than two cannot run
}

TEST(CoreFramePool, NothingPublishedGivesAnInvalidHandle) {
  FramePool pool(2, 8, 4);
  FramePool::Handle h = pool.take_latest();
  EXPECT_FALSE(h.valid());
  EXPECT_EQ(pool.frame(h).left, nullptr);
  pool.release(h);  // harmless
}

TEST(CoreFramePool, ConsumerGetsTheNewestFrameWithItsMetadata) {
  FramePool pool(3, 8, 4);
  EXPECT_EQ(produce(pool, 10), 1u);
  EXPECT_EQ(produce(pool, 11), 2u);
  FramePool::Handle h = pool.take_latest();
  ASSERT_TRUE(h.valid());
  const FramePool::Frame f = pool.frame(h);
  EXPECT_EQ(f.sequence, 11u);
  EXPECT_EQ(f.stamp, 11000);
  EXPECT_EQ(f.frame_id, 2u);
  EXPECT_EQ(h.frame_id, 2u);
  EXPECT_TRUE(check(f));
  // Nothing newer than what this consumer has: no handle, no reference.
  EXPECT_FALSE(pool.take_latest(h.frame_id).valid());
  pool.release(h);
  EXPECT_FALSE(h.valid());
  EXPECT_EQ(pool.busy(), 1);  // only the newest stays held
  EXPECT_EQ(pool.published(), 2);
}

TEST(CoreFramePool, HeldFrameIsNeverOverwrittenAndFullPoolDropsAndCounts) {
  FramePool pool(3, 8, 4);
  produce(pool, 1);
  FramePool::Handle a = pool.take_latest();  // holds frame 1
  produce(pool, 2);
  FramePool::Handle b = pool.take_latest();  // holds frame 2
  produce(pool, 3);                          // newest: frame 3; every slot now busy
  EXPECT_EQ(pool.busy(), 3);
  EXPECT_EQ(produce(pool, 4), 0u);  // no free slot: dropped
  EXPECT_EQ(produce(pool, 5), 0u);
  EXPECT_EQ(pool.dropped_full(), 2);
  EXPECT_TRUE(check(pool.frame(a)));
  EXPECT_EQ(pool.frame(a).sequence, 1u);
  EXPECT_TRUE(check(pool.frame(b)));
  EXPECT_EQ(pool.frame(b).sequence, 2u);
  // Two consumers may hold the same frame; it is freed after both let go.
  FramePool::Handle c = pool.take_latest();
  FramePool::Handle d = pool.take_latest();
  EXPECT_EQ(c.slot, d.slot);
  pool.release(a);
  EXPECT_EQ(produce(pool, 6), 4u);  // reuses frame 1's slot; drops took no id
  EXPECT_EQ(pool.frame(c).sequence, 3u);  // frame 3 lost "newest" but is still held twice
  EXPECT_TRUE(check(pool.frame(c)));
  pool.release(c);
  EXPECT_TRUE(check(pool.frame(d)));
  pool.release(d);
  pool.release(b);
  EXPECT_EQ(pool.busy(), 1);
}

TEST(CoreFramePool, AbandonedSlotIsFreeAgainAndNotPublished) {
  FramePool pool(2, 8, 4);
  FramePool::WriteSlot w = pool.acquire();
  ASSERT_TRUE(w.valid());
  pool.abandon(w);
  EXPECT_FALSE(w.valid());
  EXPECT_FALSE(pool.take_latest().valid());
  EXPECT_EQ(pool.busy(), 0);
}

TEST(CoreFramePool, NoAllocationAfterConstruction) {
  FramePool pool(4, 64, 16);
  produce(pool, 0);
  rtfuse::test::AllocScope scope;
  for (std::uint32_t s = 1; s < 200; ++s) {
    produce(pool, s);
    FramePool::Handle h = pool.take_latest();
    pool.release(h);
    pool.release(h);  // a released handle is invalid: a second release does nothing
  }
  EXPECT_EQ(scope.count(), 0u);
}

// One producer filling frames as fast as it can, one consumer taking the
// newest and checking every byte while holding it. A frame overwritten
// while held would mix two sequence numbers' patterns.
TEST(CoreFramePool, StressNoTornFrameAndNoAllocation) {
  FramePool pool(3, 96, 24);
  constexpr std::uint32_t kFrames = 20000;
  std::atomic<bool> done{false};
  std::atomic<std::int64_t> checked{0};
  std::atomic<std::int64_t> torn{0};
  std::atomic<std::int64_t> out_of_order{0};
  std::thread consumer([&] {
    std::uint64_t last_id = 0;
    std::uint32_t last_seq = 0;
    while (!done.load(std::memory_order_acquire)) {
      FramePool::Handle h = pool.take_latest(last_id);
      if (!h.valid()) continue;
      const FramePool::Frame f = pool.frame(h);
      if (!check(f)) torn.fetch_add(1);
      if (last_id != 0 && (f.frame_id <= last_id || f.sequence <= last_seq)) out_of_order.fetch_add(1);
      // Check again after a while: the producer had time to try to reuse it.
      std::this_thread::yield();
      if (!check(f)) torn.fetch_add(1);
      last_id = f.frame_id;
      last_seq = f.sequence;
      pool.release(h);
      checked.fetch_add(1);
    }
  });
  // std::thread's start-up allocates; from here on nothing may (either thread).
  const std::uint64_t allocs_before = rtfuse::test::allocation_count();
  std::int64_t published = 0;
  for (std::uint32_t s = 1; s <= kFrames; ++s) published += produce(pool, s) != 0 ? 1 : 0;
  const std::uint64_t allocs_after = rtfuse::test::allocation_count();
  done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_EQ(allocs_after - allocs_before, 0u);
  EXPECT_EQ(torn.load(), 0);
  EXPECT_EQ(out_of_order.load(), 0);
  EXPECT_GT(checked.load(), 0);
  EXPECT_EQ(published + pool.dropped_full(), static_cast<std::int64_t>(kFrames));
  EXPECT_EQ(pool.busy(), 1);
}

// The same with two consumers holding frames longer, so the producer runs
// into a full pool; and the producer's path must not allocate.
TEST(CoreFramePool, StressTwoConsumersFullPoolNoAllocationOnTheProducer) {
  FramePool pool(3, 32, 8);
  constexpr std::uint32_t kFrames = 20000;
  std::atomic<bool> done{false};
  std::atomic<std::int64_t> torn{0};
  auto consume = [&] {
    while (!done.load(std::memory_order_acquire)) {
      FramePool::Handle h = pool.take_latest();
      if (!h.valid()) continue;
      for (int k = 0; k < 3; ++k) {
        if (!check(pool.frame(h))) torn.fetch_add(1);
        std::this_thread::yield();
      }
      pool.release(h);
    }
  };
  std::thread c1(consume);
  std::thread c2(consume);
  // Both threads exist now; from here on nothing may allocate.
  const std::uint64_t before = rtfuse::test::allocation_count();
  for (std::uint32_t s = 1; s <= kFrames; ++s) produce(pool, s);
  const std::uint64_t after = rtfuse::test::allocation_count();
  done.store(true, std::memory_order_release);
  c1.join();
  c2.join();
  EXPECT_EQ(after - before, 0u);
  EXPECT_EQ(torn.load(), 0);
  EXPECT_EQ(pool.published() + pool.dropped_full(), static_cast<std::int64_t>(kFrames));
  EXPECT_EQ(pool.busy(), 1);
}

}  // namespace frame_pool_test
