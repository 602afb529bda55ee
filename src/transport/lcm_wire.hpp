#pragma once
// Reading LCM's wire format ahead of lcm-gen's decoders, which trust it:
// a decoder sizes vectors from count fields before it checks that the bytes
// are there, copies len - 1 bytes for any string length (0 and 2^31
// included), and keeps a string's embedded NULs that its encoder, which
// measures strings with strlen(), then drops (a record that decodes but
// re-encodes to fewer bytes than it announces). Every parser of outside
// bytes checks lengths here first.
#include <cstdint>
#include <cstring>

namespace rtfuse::transport::wire {

inline std::int32_t load_i32(const std::uint8_t* p) {
  const std::uint32_t v = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                          (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
  return static_cast<std::int32_t>(v);
}

inline std::int64_t load_i64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<std::int64_t>(v);
}

// The LCM string at `at` (an int32 length counting the NUL, then the bytes):
// the offset just past it, or -1 unless it lies within the `size` bytes,
// holds 0..max_chars characters, ends with its NUL and has no other.
inline int after_string(const std::uint8_t* b, int size, int at, std::int64_t max_chars) {
  if (b == nullptr || at < 0 || size - at < 4) return -1;
  const std::int32_t len = load_i32(b + at);
  if (len < 1 || len - 1 > max_chars || len > size - at - 4) return -1;
  const std::uint8_t* chars = b + at + 4;
  if (chars[len - 1] != 0 || std::memchr(chars, 0, static_cast<std::size_t>(len - 1)) != nullptr) return -1;
  return at + 4 + len;
}

// n such strings one after the other.
inline int after_strings(const std::uint8_t* b, int size, int at, int n, std::int64_t max_chars) {
  for (int i = 0; i < n && at >= 0; ++i) at = after_string(b, size, at, max_chars);
  return at;
}

}  // namespace rtfuse::transport::wire
