#pragma once
// Bounded single-producer/single-consumer queue between a sensor thread and
// the real-time loop. Lock-free and allocation-free after construction: the
// loop must never wait on, or allocate for, a producer.
//
// Exactly one thread may call the producer side (try_push) and exactly one
// the consumer side (try_pop, peek, pop). size()/empty()/capacity() are safe
// from either; size() is only a snapshot while the other side is running.
#include <atomic>
#include <cassert>
#include <cstddef>
#include <memory>
#include <type_traits>
#include <utility>

namespace rtfuse {

template <class T>
class SpscRing {
  static_assert(std::atomic<std::size_t>::is_always_lock_free,
                "the real-time path may only use lock-free atomics");
  // Slots are constructed once, up front, and reused by assignment, so that
  // push/pop never construct, destroy or allocate.
  static_assert(std::is_default_constructible_v<T>, "SpscRing<T> pre-constructs its slots");
  static_assert(std::is_copy_assignable_v<T>, "SpscRing<T> copies into its slots");

 public:
  // One extra slot tells "full" from "empty" without a shared counter that
  // both threads would write.
  explicit SpscRing(std::size_t capacity)
      : capacity_(capacity), slots_count_(capacity + 1), slots_(new T[capacity + 1]) {
    assert(capacity > 0);
  }

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;
  SpscRing(SpscRing&&) = delete;
  SpscRing& operator=(SpscRing&&) = delete;

  // Producer. False when full; the queued items are left untouched.
  bool try_push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t next = advance(tail);
    if (next == head_cache_) {
      // Only re-read the consumer's index when the stale copy says "full":
      // keeps the consumer's cache line out of the producer's hot path.
      head_cache_ = head_.load(std::memory_order_acquire);
      if (next == head_cache_) return false;
    }
    slots_[tail] = value;
    tail_.store(next, std::memory_order_release);
    return true;
  }

  // Consumer. False when empty.
  bool try_pop(T& out) noexcept {
    T* item = front();
    if (item == nullptr) return false;
    out = std::move(*item);
    pop();
    return true;
  }

  // Consumer. The front item, or nullptr when empty. The pointer stays valid
  // until pop(): the producer cannot reuse the slot before then.
  const T* peek() const noexcept { return front(); }

  // Consumer. Drops the front item; only after peek() returned non-null.
  void pop() noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    assert(head != tail_.load(std::memory_order_acquire) && "pop() on an empty SpscRing");
    head_.store(advance(head), std::memory_order_release);
  }

  std::size_t size() const noexcept {
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return tail >= head ? tail - head : tail + slots_count_ - head;
  }
  bool empty() const noexcept { return size() == 0; }
  std::size_t capacity() const noexcept { return capacity_; }

 private:
  T* front() const noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return nullptr;
    }
    return &slots_[head];
  }

  // A compare instead of '%': capacity need not be a power of two, and
  // division is slow on small ARM cores.
  std::size_t advance(std::size_t i) const noexcept { return i + 1 == slots_count_ ? 0 : i + 1; }

  static constexpr std::size_t kCacheLine = 64;

  // Read-only after construction; shared by both sides without contention.
  const std::size_t capacity_;
  const std::size_t slots_count_;
  const std::unique_ptr<T[]> slots_;  // new T[] honours alignof(T) > 16 in C++17

  // Producer-owned line: its index and its stale view of the consumer's.
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;

  // Consumer-owned line.
  alignas(kCacheLine) std::atomic<std::size_t> head_{0};
  mutable std::size_t tail_cache_ = 0;  // peek() is const but refreshes the consumer's view
  // sizeof is a multiple of alignof (64), so nothing after this object shares the line.
};

}  // namespace rtfuse
