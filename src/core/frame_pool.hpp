#pragma once
// A fixed pool of rectified stereo frames (left and right 8-bit grey images
// plus capture stamp, sequence number and frame id) lent by handle between
// one producer (the camera thread) and any number of consumers (visual
// odometry, the publisher's preview).
//
// Pixels never move through a queue: the producer fills a slot in place and
// publishes its index; consumers take the newest published slot and read it
// in place. All memory is allocated once, in the constructor.
//
// Ownership is a reference count per slot: 0 is free; the producer holds 1
// while it fills the slot; "being the newest" holds 1; every consumer handle
// holds 1. The producer only writes a slot it took from 0 to 1, and a slot
// cannot reach 0 while anyone holds it, so a frame being read is never
// overwritten. When no slot is free the producer drops the new frame (counted)
// rather than wait: the camera thread must keep draining the device.
//
// Taking the newest frame races with the producer replacing it, so a consumer
// (1) reads `latest_` (slot index + frame id in one word), (2) increments that
// slot's count only if it is not 0 (a free slot stays free), (3) re-reads
// `latest_`: unchanged means the reference is on the frame it asked for;
// changed means the slot may already hold something else, so it gives the
// reference back and retries. The frame id in the word makes (3) immune to
// the same slot being published again (ABA). The retry loop only repeats when
// a newer frame was published meanwhile (lock-free, not wait-free).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/time.hpp"

namespace rtfuse {

class FramePool {
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free, "the real-time path may only use lock-free atomics");
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "the real-time path may only use lock-free atomics");

 public:
  // The index fits in the low bits of latest_; 64 slots is far more than a
  // camera pipeline needs (a few frames in flight).
  static constexpr int kMaxSlots = 64;
  // Rows start on a cache line so the rectifier's row writes and the
  // consumers' row reads never share a line across rows of different slots.
  static constexpr int kRowAlign = 64;

  // What a consumer reads; valid until release(handle).
  struct Frame {
    const std::uint8_t* left = nullptr;
    const std::uint8_t* right = nullptr;
    int width = 0;   // one eye, pixels
    int height = 0;
    int stride = 0;  // bytes from one row to the next (>= width)
    TimeNs stamp = 0;            // capture time, CLOCK_MONOTONIC ns
    std::uint32_t sequence = 0;  // the device's frame counter
    std::uint64_t frame_id = 0;  // 1, 2, ... in publish order; never reused
  };

  // A consumer's reference to one published frame. Plain data: give it back
  // with release() exactly once.
  struct Handle {
    int slot = -1;
    std::uint64_t frame_id = 0;
    bool valid() const noexcept { return slot >= 0; }
  };

  // The producer's slot while it fills it.
  struct WriteSlot {
    std::uint8_t* left = nullptr;
    std::uint8_t* right = nullptr;
    int width = 0;
    int height = 0;
    int stride = 0;
    int slot = -1;
    bool valid() const noexcept { return slot >= 0; }
  };

  // `slots` frames of two width x height grey images (slots clamped to
  // 2..kMaxSlots: one being filled plus one published is the least that lets
  // the producer run while a consumer reads). Allocates; start-up only.
  FramePool(int slots, int width, int height)
      : slots_(clamp_slots(slots)),
        width_(width > 0 ? width : 0),
        height_(height > 0 ? height : 0),
        stride_(round_up(width_, kRowAlign)),
        image_bytes_(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(height_)),
        storage_(new std::uint8_t[image_bytes_ * 2u * static_cast<std::size_t>(slots_) + kRowAlign]()),
        meta_(new Meta[static_cast<std::size_t>(slots_)]),
        refs_(new std::atomic<std::uint32_t>[static_cast<std::size_t>(slots_)]) {
    // new[] only promises alignof(max_align_t); align the images by hand.
    const auto base = reinterpret_cast<std::uintptr_t>(storage_.get());
    base_ = storage_.get() + (round_up_ptr(base, kRowAlign) - base);
    for (int i = 0; i < slots_; ++i) refs_[i].store(0, std::memory_order_relaxed);
  }
  FramePool(const FramePool&) = delete;
  FramePool& operator=(const FramePool&) = delete;

  int slots() const noexcept { return slots_; }
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  int stride() const noexcept { return stride_; }

  // --- producer (one thread) ---

  // A free slot to fill, or an invalid WriteSlot when every slot is held
  // (the frame is then dropped and counted in dropped_full()).
  WriteSlot acquire() noexcept {
    // Start after the slot used last so slots rotate (no reason to prefer
    // any; rotating keeps a just-released slot's lines cold for the reader).
    for (int k = 0; k < slots_; ++k) {
      const int i = (next_scan_ + k) % slots_;
      std::uint32_t expected = 0;
      // acq_rel: acquire pairs with the last holder's release (its reads are
      // done before we write); release orders this 0 -> 1 before the
      // publish of `latest_` that unpublished the slot, for step (3) above.
      if (refs_[i].compare_exchange_strong(expected, 1, std::memory_order_acq_rel, std::memory_order_relaxed)) {
        next_scan_ = (i + 1) % slots_;
        WriteSlot w;
        w.left = left_of(i);
        w.right = right_of(i);
        w.width = width_;
        w.height = height_;
        w.stride = stride_;
        w.slot = i;
        return w;
      }
    }
    dropped_full_.fetch_add(1, std::memory_order_relaxed);
    return WriteSlot{};
  }

  // Makes a filled slot the newest frame; the previous newest loses the
  // pool's reference (freed unless a consumer still holds it). Returns the
  // new frame's id.
  std::uint64_t publish(WriteSlot& w, TimeNs stamp, std::uint32_t sequence) noexcept {
    const std::uint64_t id = ++last_id_;
    Meta& m = meta_[w.slot];
    m.stamp = stamp;
    m.sequence = sequence;
    m.frame_id = id;
    // The producer's reference becomes the "newest" reference: no count change.
    const std::uint64_t old = latest_.exchange(pack(w.slot, id), std::memory_order_acq_rel);
    if (old != 0) unref(slot_of(old));
    published_.fetch_add(1, std::memory_order_relaxed);
    w = WriteSlot{};
    return id;
  }

  // Gives back a slot that will not be published (e.g. the frame was bad).
  void abandon(WriteSlot& w) noexcept {
    if (w.valid()) unref(w.slot);
    w = WriteSlot{};
  }

  // --- consumers (any threads) ---

  // The newest published frame, or an invalid handle when nothing has been
  // published or the newest has id <= newer_than (nothing new for this
  // consumer; no reference is taken then).
  Handle take_latest(std::uint64_t newer_than = 0) noexcept {
    std::uint64_t word = latest_.load(std::memory_order_acquire);
    for (;;) {
      if (word == 0 || id_of(word) <= newer_than) return Handle{};
      const int i = slot_of(word);
      std::uint32_t n = refs_[i].load(std::memory_order_relaxed);
      bool got = false;
      while (n != 0) {
        // Never from 0: a free slot belongs to the producer's next acquire().
        if (refs_[i].compare_exchange_weak(n, n + 1, std::memory_order_acq_rel, std::memory_order_relaxed)) {
          got = true;
          break;
        }
      }
      const std::uint64_t now = latest_.load(std::memory_order_acquire);
      if (got && now == word) return Handle{i, id_of(word)};
      if (got) unref(i);
      word = now;
    }
  }

  // The frame a handle refers to (invalid handle: an empty Frame).
  Frame frame(const Handle& h) const noexcept {
    Frame f;
    if (!h.valid()) return f;
    const Meta& m = meta_[h.slot];
    f.left = left_of(h.slot);
    f.right = right_of(h.slot);
    f.width = width_;
    f.height = height_;
    f.stride = stride_;
    f.stamp = m.stamp;
    f.sequence = m.sequence;
    f.frame_id = m.frame_id;
    return f;
  }

  // A second reference to a frame the caller holds (a consumer keeping a
  // pair it was lent for the length of a call). Never fails: the slot's
  // count is at least the caller's 1, so it cannot be free.
  Handle retain(const Handle& h) noexcept {
    if (!h.valid()) return Handle{};
    refs_[h.slot].fetch_add(1, std::memory_order_relaxed);
    return h;
  }

  // Gives a frame back; the handle becomes invalid.
  void release(Handle& h) noexcept {
    if (h.valid()) unref(h.slot);
    h = Handle{};
  }

  // --- statistics (any thread; snapshots) ---
  std::int64_t published() const noexcept { return published_.load(std::memory_order_relaxed); }
  std::int64_t dropped_full() const noexcept { return dropped_full_.load(std::memory_order_relaxed); }
  // Slots currently held by anyone (producer, newest, consumers).
  int busy() const noexcept {
    int n = 0;
    for (int i = 0; i < slots_; ++i) n += refs_[i].load(std::memory_order_relaxed) != 0 ? 1 : 0;
    return n;
  }

 private:
  // Written by the producer only while it holds the slot alone; read by
  // consumers only while they hold a reference, so plain fields suffice.
  struct Meta {
    TimeNs stamp = 0;
    std::uint32_t sequence = 0;
    std::uint64_t frame_id = 0;
  };

  static constexpr int kSlotBits = 8;  // > log2(kMaxSlots)
  static std::uint64_t pack(int slot, std::uint64_t id) noexcept {
    return (id << kSlotBits) | static_cast<std::uint64_t>(slot);
  }
  static int slot_of(std::uint64_t word) noexcept { return static_cast<int>(word & ((1u << kSlotBits) - 1u)); }
  static std::uint64_t id_of(std::uint64_t word) noexcept { return word >> kSlotBits; }
  static int clamp_slots(int n) noexcept { return n < 2 ? 2 : (n > kMaxSlots ? kMaxSlots : n); }
  static int round_up(int v, int a) noexcept { return (v + a - 1) / a * a; }
  static std::uintptr_t round_up_ptr(std::uintptr_t v, std::uintptr_t a) noexcept { return (v + a - 1) / a * a; }

  void unref(int i) noexcept {
    // release: this holder's reads of the slot happen before the producer's
    // next acquire() (acquire CAS) writes it.
    refs_[i].fetch_sub(1, std::memory_order_acq_rel);
  }
  std::uint8_t* left_of(int i) const noexcept { return base_ + image_bytes_ * 2u * static_cast<std::size_t>(i); }
  std::uint8_t* right_of(int i) const noexcept { return left_of(i) + image_bytes_; }

  const int slots_;
  const int width_;
  const int height_;
  const int stride_;
  const std::size_t image_bytes_;
  const std::unique_ptr<std::uint8_t[]> storage_;
  std::uint8_t* base_ = nullptr;
  const std::unique_ptr<Meta[]> meta_;
  const std::unique_ptr<std::atomic<std::uint32_t>[]> refs_;

  // Producer-only.
  int next_scan_ = 0;
  std::uint64_t last_id_ = 0;

  // Slot index (low kSlotBits) and frame id of the newest frame; 0: none yet
  // (ids start at 1, so a published word is never 0).
  alignas(64) std::atomic<std::uint64_t> latest_{0};
  alignas(64) std::atomic<std::int64_t> published_{0};
  std::atomic<std::int64_t> dropped_full_{0};
};

}  // namespace rtfuse
