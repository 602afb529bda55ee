// XXH64: the specification's values (checked against the reference
// libxxhash 0.8.1 when these were written), so a platform or compiler that
// computes it differently fails here, in the aarch64 stage too; and the
// streaming form equals the one-shot digest however the bytes are split.
#include "core/xxh64.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace rtfuse {
namespace xxh64_test {

std::vector<std::uint8_t> pattern(std::size_t n) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return v;
}

TEST(Xxh64, KnownAnswers) {
  EXPECT_EQ(xxh64(nullptr, 0), 0xEF46DB3751D8E999ULL);
  EXPECT_EQ(xxh64("abc", 3), 0x44BC2CF5AD770999ULL);
  // 100 bytes: three whole stripes, then an 8-byte word and a 4-byte word in the tail.
  const std::vector<std::uint8_t> p = pattern(100);
  EXPECT_EQ(xxh64(p.data(), p.size()), 0xA61F8D4C170FE531ULL);
  EXPECT_EQ(xxh64(p.data(), p.size(), 0x9E3779B97F4A7C15ULL), 0xF6D8F65C625ABB4FULL);
}

TEST(Xxh64, StreamingEqualsOneShotForEverySplit) {
  const std::vector<std::uint8_t> p = pattern(161);
  for (std::size_t n : {0u, 1u, 31u, 32u, 33u, 64u, 100u, 161u}) {
    const std::uint64_t want = xxh64(p.data(), n, 42);
    for (std::size_t chunk = 1; chunk <= 40; ++chunk) {
      Xxh64 h(42);
      for (std::size_t o = 0; o < n; o += chunk) h.update(p.data() + o, n - o < chunk ? n - o : chunk);
      EXPECT_EQ(h.digest(), want) << n << " bytes in pieces of " << chunk;
    }
  }
}

TEST(Xxh64, EveryByteAndTheSeedCount) {
  std::vector<std::uint8_t> p = pattern(100);
  const std::uint64_t base = xxh64(p.data(), p.size());
  EXPECT_NE(xxh64(p.data(), p.size(), 1), base);
  EXPECT_NE(xxh64(p.data(), p.size() - 1), base);
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i] ^= 0x01;
    EXPECT_NE(xxh64(p.data(), p.size()), base) << "byte " << i;
    p[i] ^= 0x01;
  }
  // digest() does not end the stream.
  Xxh64 h;
  h.update(p.data(), 50);
  (void)h.digest();
  h.update(p.data() + 50, 50);
  EXPECT_EQ(h.digest(), base);
}

}  // namespace xxh64_test
}  // namespace rtfuse
