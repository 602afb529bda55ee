#pragma once
// Latest-value cell: one writer (the real-time loop) publishes, any number of
// readers (publisher, diagnostics) copy. The writer never waits for readers;
// a reader that overlaps a write retries.
//
// The payload lives in atomic words, not in a plain T: a reader racing the
// writer on plain memory would be a data race (undefined behaviour, and
// flagged by ThreadSanitizer) even though the sequence check discards the
// torn copy afterwards. Relaxed word accesses plus fences cost the same
// instructions as memcpy on x86 and aarch64.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace rtfuse {

template <class T>
class SeqLock {
  static_assert(std::is_trivially_copyable_v<T>,
                "SeqLock<T> copies T as raw words (note: Eigen matrices are not trivially copyable)");
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free,
                "the real-time path may only use lock-free atomics");

  using Word = std::uint64_t;
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(Word) - 1) / sizeof(Word);

 public:
  // Until the first store(), readers see a T made of zero bytes; version() is 0.
  SeqLock() noexcept {
    for (auto& w : words_) w.store(0, std::memory_order_relaxed);
  }
  SeqLock(const SeqLock&) = delete;
  SeqLock& operator=(const SeqLock&) = delete;

  // Writer side. Only one thread may call it.
  void store(const T& value) noexcept {
    const std::uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
    fence_release();  // readers who see any new word must also see the odd sequence
    const auto* src = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t i = 0; i < kWords; ++i) {
      words_[i].store(pack(src, i), kWordStore);
    }
    seq_.store(seq + 2, std::memory_order_release);
  }

  // One attempt. False when it overlapped a write; `out` is then untouched.
  bool try_load(T& out) const noexcept {
    alignas(T) unsigned char buf[sizeof(T)];
    if (!read(buf)) return false;
    std::memcpy(&out, buf, sizeof(T));
    return true;
  }

  // Retries until it gets a copy no write overlapped. Lock-free for the
  // writer; a reader can only starve if the writer stores back to back.
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
    if (before & 1U) return false;
    for (std::size_t i = 0; i < kWords; ++i) {
      unpack(words_[i].load(kWordLoad), dst, i);
    }
    fence_acquire();  // the words above are read before the sequence below
    return seq_.load(std::memory_order_relaxed) == before;
  }

  // The last word of T may be partial: never read or write past sizeof(T).
  static constexpr std::size_t bytes_in(std::size_t i) noexcept {
    return (i + 1) * sizeof(Word) <= sizeof(T) ? sizeof(Word) : sizeof(T) - i * sizeof(Word);
  }
  static Word pack(const unsigned char* src, std::size_t i) noexcept {
    Word w = 0;
    std::memcpy(&w, src + i * sizeof(Word), bytes_in(i));
    return w;
  }
  static void unpack(Word w, unsigned char* dst, std::size_t i) noexcept {
    std::memcpy(dst + i * sizeof(Word), &w, bytes_in(i));
  }

  // ThreadSanitizer checks this same code: every access to the payload is
  // atomic, so it finds any plain memory shared between the threads; it
  // does not model the two fences, whose ordering it therefore takes on
  // trust (docs/reliability.md).
  static constexpr std::memory_order kWordStore = std::memory_order_relaxed;
  static constexpr std::memory_order kWordLoad = std::memory_order_relaxed;
  static void fence_release() noexcept { std::atomic_thread_fence(std::memory_order_release); }
  static void fence_acquire() noexcept { std::atomic_thread_fence(std::memory_order_acquire); }

  std::atomic<std::uint64_t> seq_{0};  // even: stable, odd: write in progress
  std::atomic<Word> words_[kWords];
};

}  // namespace rtfuse
