// The mailbox between a frame source's thread and a consumer on a thread of
// its own: the newest pair waits, an older one is dropped and counted, and
// no reference leaks, so the pool's slots always come back.
#include "core/frame_mailbox.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace rtfuse {
namespace frame_mailbox_test {

// Publishes one frame and returns a handle the caller holds, as a source
// does around on_pair().
FramePool::Handle publish(FramePool& pool, std::uint8_t value, TimeNs stamp) {
  FramePool::WriteSlot w = pool.acquire();
  EXPECT_TRUE(w.valid());
  for (int y = 0; y < w.height; ++y) w.left[y * w.stride] = value;
  pool.publish(w, stamp, static_cast<std::uint32_t>(stamp));
  return pool.take_latest();
}

TEST(FrameMailbox, TheConsumerGetsTheNewestPairAndTheOlderOneIsDroppedAndCounted) {
  FramePool pool(6, 8, 4);
  FrameMailbox box;
  for (std::uint8_t v = 1; v <= 3; ++v) {
    FramePool::Handle h = publish(pool, v, v);
    box.offer(pool, h);
    pool.release(h);
  }
  EXPECT_EQ(box.offered(), 3);
  EXPECT_EQ(box.dropped(), 2);
  FramePool::Handle got = box.take();
  ASSERT_TRUE(got.valid());
  EXPECT_EQ(pool.frame(got).left[0], 3);
  EXPECT_EQ(pool.frame(got).stamp, 3);
  // Nothing waits any more.
  EXPECT_FALSE(box.take().valid());
  pool.release(got);
  // Only the pool's own newest frame is held: no reference leaked.
  EXPECT_EQ(pool.busy(), 1);
}

TEST(FrameMailbox, AWaitingPairKeepsItsSlotUntilTakenOrCleared) {
  FramePool pool(3, 8, 4);
  FrameMailbox box;
  FramePool::Handle h = publish(pool, 7, 1);
  box.offer(pool, h);
  pool.release(h);
  // The waiting pair is not the newest any more, yet it stays intact.
  FramePool::Handle n = publish(pool, 9, 2);
  pool.release(n);
  EXPECT_EQ(pool.busy(), 2);
  FramePool::Handle w = box.take();
  ASSERT_TRUE(w.valid());
  EXPECT_EQ(pool.frame(w).left[0], 7);
  pool.release(w);
  EXPECT_EQ(pool.busy(), 1);
  // Cleared at shutdown: the slot comes back.
  FramePool::Handle m = publish(pool, 11, 3);
  box.offer(pool, m);
  pool.release(m);
  box.clear(pool);
  EXPECT_EQ(pool.busy(), 1);
  EXPECT_EQ(box.dropped(), 0);
}

TEST(FrameMailbox, ASlowConsumerNeverStarvesTheProducer) {
  // Producer: fill, newest; consumer: one waiting and one in work.
  FramePool pool(4, 16, 4);
  FrameMailbox box;
  std::atomic<bool> stop{false};
  std::atomic<std::int64_t> taken{0};
  std::thread consumer([&] {
    while (!stop.load()) {
      FramePool::Handle h = box.take();
      if (!h.valid()) continue;
      const FramePool::Frame f = pool.frame(h);
      std::uint32_t sum = 0;
      for (int i = 0; i < 2000; ++i) sum += f.left[i % (f.stride * f.height)];
      if (sum > 0) taken.fetch_add(1);
      pool.release(h);
    }
  });
  // Until the consumer has worked on a good many pairs while the producer
  // ran flat out; on a loaded machine its thread may get little time, so
  // the bound is a time, not a count.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  std::int64_t produced = 0;
  for (; produced < 20000 || (taken.load() < 200 && std::chrono::steady_clock::now() < give_up); ++produced) {
    FramePool::WriteSlot w = pool.acquire();
    ASSERT_TRUE(w.valid()) << "the producer found no free slot at frame " << produced;
    w.left[0] = 1;
    pool.publish(w, produced, static_cast<std::uint32_t>(produced));
    FramePool::Handle h = pool.take_latest();
    box.offer(pool, h);
    pool.release(h);
  }
  stop = true;
  consumer.join();
  box.clear(pool);
  EXPECT_EQ(pool.dropped_full(), 0);
  EXPECT_GE(taken.load(), 200);
  EXPECT_EQ(box.offered(), produced);
  EXPECT_GT(box.dropped(), 0);
  EXPECT_EQ(pool.busy(), 1);
}

}  // namespace frame_mailbox_test
}  // namespace rtfuse
