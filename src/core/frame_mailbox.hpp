#pragma once
// One pair of a FramePool waiting for a consumer on a thread of its own. The source's
// thread leaves the newest pair (FrameSource's on_pair, never blocking); the
// consumer takes it when it is ready. A pair the consumer did not take in
// time is replaced by the newer one and counted as dropped, so a slow
// consumer always works on the newest pair and holds at most two (the one
// waiting and the one in work).
//
// Lock-free: the waiting pair is one atomic word (slot and frame id), swapped
// by either side.
#include <atomic>
#include <cstdint>

#include "core/frame_pool.hpp"

namespace rtfuse {

class FrameMailbox {
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "the real-time path may only use lock-free atomics");
  static_assert(std::atomic<std::int64_t>::is_always_lock_free, "the real-time path may only use lock-free atomics");

 public:
  FrameMailbox() = default;
  FrameMailbox(const FrameMailbox&) = delete;
  FrameMailbox& operator=(const FrameMailbox&) = delete;

  // Source thread: keeps its own reference to `newest` for the consumer.
  void offer(FramePool& pool, const FramePool::Handle& newest) noexcept {
    if (!newest.valid()) return;
    const FramePool::Handle mine = pool.retain(newest);
    offered_.fetch_add(1, std::memory_order_relaxed);
    const std::uint64_t old = waiting_.exchange(pack(mine), std::memory_order_acq_rel);
    if (old == 0) return;
    FramePool::Handle stale = unpack(old);
    pool.release(stale);
    dropped_.fetch_add(1, std::memory_order_relaxed);
  }

  // Consumer thread: the waiting pair (invalid when none). Give it back with
  // pool.release() when done.
  FramePool::Handle take() noexcept { return unpack(waiting_.exchange(0, std::memory_order_acq_rel)); }

  // At shutdown, after both threads stopped: the waiting pair's reference.
  void clear(FramePool& pool) noexcept {
    FramePool::Handle h = take();
    pool.release(h);
  }

  std::int64_t offered() const noexcept { return offered_.load(std::memory_order_relaxed); }
  std::int64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  // Frame ids start at 1, so a packed handle is never 0.
  static constexpr int kSlotBits = 8;
  static std::uint64_t pack(const FramePool::Handle& h) noexcept {
    return (h.frame_id << kSlotBits) | static_cast<std::uint64_t>(h.slot);
  }
  static FramePool::Handle unpack(std::uint64_t w) noexcept {
    if (w == 0) return FramePool::Handle{};
    return FramePool::Handle{static_cast<int>(w & ((1u << kSlotBits) - 1u)), w >> kSlotBits};
  }

  std::atomic<std::uint64_t> waiting_{0};
  std::atomic<std::int64_t> offered_{0};
  std::atomic<std::int64_t> dropped_{0};
};

}  // namespace rtfuse
