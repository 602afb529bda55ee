#pragma once
// Encoding lcm-gen messages into caller-owned storage, so a publisher can
// encode and lcm_publish without touching the heap.
#include <array>
#include <cstddef>
#include <cstdint>

namespace rtfuse::transport {

// Bytes written, or -1 when the message does not fit in capacity.
template <class Msg>
int encode_into(const Msg& m, std::uint8_t* buf, int capacity) {
  if (buf == nullptr || capacity < 0) return -1;
  const int n = m.encode(buf, 0, capacity);
  return n < 0 ? -1 : n;
}

template <std::size_t N>
class EncodeBuffer {
  static_assert(N > 0 && N <= 0x7FFFFFFF, "LCM encodes with int sizes");

 public:
  // False (and size() 0) when the message does not fit.
  template <class Msg>
  bool encode(const Msg& m) {
    const int n = encode_into(m, bytes_.data(), static_cast<int>(N));
    size_ = n < 0 ? 0 : n;
    return n >= 0;
  }

  const std::uint8_t* data() const { return bytes_.data(); }
  std::uint8_t* data() { return bytes_.data(); }
  int size() const { return size_; }
  static constexpr int capacity() { return static_cast<int>(N); }

 private:
  std::array<std::uint8_t, N> bytes_{};
  int size_ = 0;
};

}  // namespace rtfuse::transport
