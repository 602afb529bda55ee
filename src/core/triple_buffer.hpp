#pragma once
// Latest-value hand-over of a large object (a map's 2-D grid) from one
// writer thread to one reader thread, neither ever waiting: three buffers,
// one the writer's, one the reader's, one waiting in between. The writer
// fills its own and swaps it with the waiting one; the reader, when the
// waiting one is newer than what it has, swaps its own with it. An object
// the reader has not taken yet is replaced by the newer one (latest value,
// like a seqlock), but unlike a seqlock nothing is copied: the reader works
// in place on a buffer no one else touches.
//
// Lock-free: the waiting buffer's index and a "fresh" bit are one atomic
// byte, exchanged by either side. The buffers are made by the caller at
// start-up (buffer(i)) and never move.
#include <atomic>
#include <cstdint>

namespace rtfuse {

template <class T>
class TripleBuffer {
  static_assert(std::atomic<std::uint8_t>::is_always_lock_free, "the real-time path may only use lock-free atomics");

 public:
  TripleBuffer() = default;
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Start-up only, before either thread uses it: to size the buffers.
  T& buffer(int i) noexcept { return buffers_[i]; }

  // --- writer ---
  T& write_buffer() noexcept { return buffers_[write_]; }
  // Hands write_buffer() over; the writer gets another to fill.
  void publish() noexcept {
    write_ = static_cast<std::uint8_t>(waiting_.exchange(static_cast<std::uint8_t>(write_ | kFresh),
                                                         std::memory_order_acq_rel) &
                                       kIndex);
  }

  // --- reader ---
  // The newest published object, or null when nothing was published since
  // the last call. Valid until the next call.
  const T* take_newest() noexcept {
    if ((waiting_.load(std::memory_order_relaxed) & kFresh) == 0) return nullptr;
    read_ = static_cast<std::uint8_t>(waiting_.exchange(read_, std::memory_order_acq_rel) & kIndex);
    return &buffers_[read_];
  }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;

  T buffers_[3];
  std::uint8_t write_ = 0;                 // writer's
  std::uint8_t read_ = 1;                  // reader's
  std::atomic<std::uint8_t> waiting_{2};   // between them, | kFresh when unread
};

}  // namespace rtfuse
