#pragma once
// Latest-value cells: one writer publishes, any number of readers copy; the
// writer never waits for readers, and a reader that overlaps a write
// retries. Two kinds, by who may stop the writer mid-store:
//
// SeqLock<T>, one copy, for a writer no reader can stop: the real-time loop
// publishing to the publisher and diagnostics, which run below it. Its
// sequence is odd while it writes, and readers retry until it is even.
//
// SeqLatch<T>, two copies (Linux's seqcount latch), for a writer below its
// readers: a device thread publishing its health to the loop. With one
// copy, the loop preempting the device thread mid-store on the same CPU
// would spin on the odd sequence forever, the writer never scheduled again
// (seen: rtfused at 94 % CPU, its loop in SeqLock::load, the IMU's thread
// stopped inside store); on another CPU it waits as long as the writer
// stays descheduled. Here the writer rewrites one copy while the sequence
// sends readers to the other, then the other way round: a reader retries
// only when the writer has moved on to the copy it was reading, which
// needs the writer to run, and a stopped writer leaves one copy whole. The
// price is a second copy per store, so the loop's 20 kB snapshot stays a
// SeqLock.
#include <atomic>
#include <cstdint>
#include <cstring>

#include "core/atomic_words.hpp"

namespace rtfuse {

template <class T, int kCopies>
class SeqCell {
  static_assert(kCopies == 1 || kCopies == 2, "a seqlock (1) or a latch (2)");
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free,
                "the real-time path may only use lock-free atomics");

 public:
  // Until the first store(), readers see a T made of zero bytes; version() is 0.
  SeqCell() noexcept = default;
  SeqCell(const SeqCell&) = delete;
  SeqCell& operator=(const SeqCell&) = delete;

  // Writer side. Only one thread may call it.
  void store(const T& value) noexcept {
    const std::uint64_t seq = seq_.load(std::memory_order_relaxed);
    for (int copy = 0; copy < kCopies; ++copy) {
      // Odd: readers keep off copy 0 (a latch's read copy 1); even: off
      // copy 1. Release: the copy they turn to was written before.
      seq_.store(seq + 1 + static_cast<std::uint64_t>(copy), std::memory_order_release);
      fence_release();  // readers who see any new word of this copy see the sequence that turned them away
      copies_[copy].store(value);
    }
    if (kCopies == 1) seq_.store(seq + 2, std::memory_order_release);
  }

  // One attempt. False when it overlapped a write (a latch: when the
  // writer moved on to the copy it read); `out` is then untouched.
  bool try_load(T& out) const noexcept {
    alignas(T) unsigned char buf[sizeof(T)];
    if (!read(buf)) return false;
    std::memcpy(&out, buf, sizeof(T));
    return true;
  }

  // Retries until it gets a copy no write overlapped: lock-free for the
  // writer; a reader starves only while the writer stores back to back.
  void load(T& out) const noexcept {
    auto* dst = reinterpret_cast<unsigned char*>(&out);
    while (!read(dst)) {
    }
  }

  // Number of completed store() calls: lets a reader skip an unchanged value.
  std::uint64_t version() const noexcept { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  bool read(unsigned char* dst) const noexcept {
    const std::uint64_t before = seq_.load(std::memory_order_acquire);
    if (kCopies == 1 && (before & 1U)) return false;
    copies_[kCopies == 1 ? 0 : before & 1U].load(dst);
    fence_acquire();  // the words above are read before the sequence below
    return seq_.load(std::memory_order_relaxed) == before;
  }

  // ThreadSanitizer checks this same code: every access to the payload is
  // atomic, so it finds any plain memory shared between the threads; it
  // does not model the two fences, whose ordering it therefore takes on
  // trust (docs/reliability.md).
  static void fence_release() noexcept { std::atomic_thread_fence(std::memory_order_release); }
  static void fence_acquire() noexcept { std::atomic_thread_fence(std::memory_order_acquire); }

  std::atomic<std::uint64_t> seq_{0};
  AtomicWords<T> copies_[kCopies];
};

template <class T>
using SeqLock = SeqCell<T, 1>;
template <class T>
using SeqLatch = SeqCell<T, 2>;

}  // namespace rtfuse
