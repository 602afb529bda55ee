// The tests' counting operator new counts every form of new, and every
// pointer it hands out goes back through the matching delete: a nothrow
// form left to the C++ runtime went uncounted, and under ASan its delete
// was an alloc-dealloc mismatch (issue 11, defect 7).
#include "support/alloc_counter.hpp"

#include <gtest/gtest.h>

#include <new>

namespace rtfuse::test {
namespace alloc_counter_test {

struct alignas(64) Wide {
  char bytes[64];
};

// The pointers are volatile: a new/delete pair the compiler can see through
// may be elided.
template <class F>
std::uint64_t allocations_of(F f) {
  const std::uint64_t before = allocation_count();
  f();
  return allocation_count() - before;
}

TEST(AllocCounter, CountsEveryFormOfNew) {
  EXPECT_EQ(allocations_of([] {
              int* volatile p = new int(1);
              delete p;
            }),
            1u);
  EXPECT_EQ(allocations_of([] {
              int* volatile p = new int[4];
              delete[] p;
            }),
            1u);
  EXPECT_EQ(allocations_of([] {
              int* volatile p = new (std::nothrow) int(2);
              ASSERT_NE(p, nullptr);
              delete p;
            }),
            1u);
  EXPECT_EQ(allocations_of([] {
              int* volatile p = new (std::nothrow) int[8];
              ASSERT_NE(p, nullptr);
              delete[] p;
            }),
            1u);
  EXPECT_EQ(allocations_of([] {
              Wide* volatile p = new Wide;
              EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % 64, 0u);
              delete p;
            }),
            1u);
  EXPECT_EQ(allocations_of([] {
              Wide* volatile p = new (std::nothrow) Wide[3];
              ASSERT_NE(p, nullptr);
              EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % 64, 0u);
              delete[] p;
            }),
            1u);
}

TEST(AllocCounter, AScopeCountsOnlyWhileArmed) {
  int* early = new (std::nothrow) int(0);
  std::size_t inside = 0;
  {
    AllocScope scope;
    int* volatile p = new (std::nothrow) int(3);
    delete p;
    inside = scope.count();
  }
  delete early;
  EXPECT_EQ(inside, 1u);
}

}  // namespace alloc_counter_test
}  // namespace rtfuse::test
