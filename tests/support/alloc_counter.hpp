#pragma once
// Counts global operator new calls while armed. Include in exactly one
// translation unit per test executable through alloc_counter.cpp.
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace rtfuse::test {

struct AllocCounter {
  static std::atomic<bool> armed;
  static std::atomic<std::size_t> count;
};

// Every operator new since the program started, armed or not: tests compare
// it before and after the calls they check.
std::uint64_t allocation_count() noexcept;

// Counts allocations made between construction and count().
class AllocScope {
 public:
  AllocScope() {
    AllocCounter::count.store(0);
    AllocCounter::armed.store(true);
  }
  ~AllocScope() { AllocCounter::armed.store(false); }
  std::size_t count() const { return AllocCounter::count.load(); }
};

}  // namespace rtfuse::test
