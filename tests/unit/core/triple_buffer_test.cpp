// The grid's hand-over from the mapper's thread to the publisher's: the
// reader gets the newest object once, never one being written, and neither
// side waits.
#include "core/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

namespace triple_buffer_test {
using rtfuse::TripleBuffer;

struct Big {
  std::uint64_t version = 0;
  std::uint64_t words[512] = {};
};

TEST(TripleBuffer, TheReaderGetsTheNewestOnceAndNothingWhenNoneIsNew) {
  TripleBuffer<int> b;
  EXPECT_EQ(b.take_newest(), nullptr);
  b.write_buffer() = 1;
  b.publish();
  b.write_buffer() = 2;
  b.publish();
  const int* got = b.take_newest();
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(*got, 2);  // 1 was replaced before it was read
  EXPECT_EQ(b.take_newest(), nullptr);
  b.write_buffer() = 3;
  b.publish();
  got = b.take_newest();
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(*got, 3);
}

// Two threads: every object the reader sees is whole (all its words one
// version) and versions only increase. Under ThreadSanitizer, a race on
// the buffers would be reported.
TEST(TripleBuffer, TwoThreadsNeverShareABuffer) {
  TripleBuffer<Big> b;
  constexpr std::uint64_t kVersions = 20000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t v = 1; v <= kVersions; ++v) {
      Big& w = b.write_buffer();
      w.version = v;
      for (std::uint64_t& x : w.words) x = v;
      b.publish();
    }
    done.store(true);
  });
  std::uint64_t last = 0, seen = 0;
  bool torn = false, backwards = false;
  for (;;) {
    // done before an empty take: every publish came before the take.
    const bool finished = done.load();
    const Big* r = b.take_newest();
    if (r == nullptr) {
      if (finished) break;
      continue;
    }
    ++seen;
    for (std::uint64_t x : r->words) torn = torn || x != r->version;
    backwards = backwards || r->version <= last;
    last = r->version;
  }
  writer.join();
  EXPECT_FALSE(torn);
  EXPECT_FALSE(backwards);
  EXPECT_GT(seen, 0u);
  EXPECT_EQ(last, kVersions);  // the last one published is never lost
}

}  // namespace triple_buffer_test
