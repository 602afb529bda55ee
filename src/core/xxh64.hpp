#pragma once
// XXH64 (Yann Collet's xxHash, 64-bit variant), streaming: a 64-bit digest of
// bytes fed in pieces of any size, equal to the one-shot digest of the same
// bytes in one piece. A fast, well-mixed checksum to tell whether two byte
// streams are the same (a replay reproducing a camera's output); not a
// cryptographic hash.
//
// Debian's xxHash (libxxhash-dev), inlined (XXH_INLINE_ALL): no library at
// run time, and the state lives in this object (XXH64_createState would
// allocate). XXH64 is integer-only and reads its input as little-endian
// words on every host, so it gives the same value on x86-64 and aarch64.
#include <cstddef>
#include <cstdint>

#ifndef XXH_INLINE_ALL
#define XXH_INLINE_ALL
#endif
#include <xxhash.h>

namespace rtfuse {

class Xxh64 {
 public:
  explicit Xxh64(std::uint64_t seed = 0) noexcept { reset(seed); }

  void reset(std::uint64_t seed = 0) noexcept { XXH64_reset(&state_, seed); }
  void update(const void* data, std::size_t n) noexcept {
    if (n > 0) XXH64_update(&state_, data, n);
  }
  // The digest of everything fed since the seed; feeding may go on after.
  std::uint64_t digest() const noexcept { return XXH64_digest(&state_); }

 private:
  XXH64_state_t state_;
};

// One-shot.
inline std::uint64_t xxh64(const void* data, std::size_t n, std::uint64_t seed = 0) noexcept {
  return XXH64(n > 0 ? data : "", n, seed);
}

}  // namespace rtfuse
