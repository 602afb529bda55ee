#pragma once
// A trivially copyable T held as relaxed atomic 64-bit words: the payload
// of the latest-value cells (seq_cell.hpp), whose readers may copy it
// while a writer overwrites it and then discard the copy.
//
// Atomic words, not a plain T: a reader racing the writer on plain memory
// would be a data race (undefined behaviour, and flagged by
// ThreadSanitizer) even though the sequence check discards the torn copy
// afterwards. Relaxed word accesses cost the same instructions as memcpy
// on x86 and aarch64; the cells order them with fences.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace rtfuse {

template <class T>
class AtomicWords {
  static_assert(std::is_trivially_copyable_v<T>,
                "AtomicWords<T> copies T as raw words (note: Eigen matrices are not trivially copyable)");
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free,
                "the real-time path may only use lock-free atomics");

  using Word = std::uint64_t;
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(Word) - 1) / sizeof(Word);

 public:
  // Zero bytes until the first store().
  AtomicWords() noexcept {
    for (auto& w : words_) w.store(0, std::memory_order_relaxed);
  }
  AtomicWords(const AtomicWords&) = delete;
  AtomicWords& operator=(const AtomicWords&) = delete;

  void store(const T& value) noexcept {
    const auto* src = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(pack(src, i), std::memory_order_relaxed);
  }

  // Copies sizeof(T) bytes to dst, which may be torn if a store overlaps.
  void load(unsigned char* dst) const noexcept {
    for (std::size_t i = 0; i < kWords; ++i) unpack(words_[i].load(std::memory_order_relaxed), dst, i);
  }

 private:
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

  std::atomic<Word> words_[kWords];
};

}  // namespace rtfuse
