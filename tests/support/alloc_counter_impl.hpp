#pragma once
// Replaces the global operator new/delete so tests can count allocations.
// Include from exactly one .cpp of a test executable.
#include <cstdlib>
#include <new>

#include "support/alloc_counter.hpp"

namespace rtfuse::test {
std::atomic<bool> AllocCounter::armed{false};
std::atomic<std::size_t> AllocCounter::count{0};
namespace {
std::atomic<std::uint64_t> g_total_allocations{0};
}
std::uint64_t allocation_count() noexcept { return g_total_allocations.load(std::memory_order_relaxed); }
}  // namespace rtfuse::test

// Every form of the global operator new and delete is replaced, the nothrow
// ones included: a form left to the runtime would go uncounted, and under
// ASan its pointer would come back to our free() (alloc-dealloc-mismatch).
static void* rtfuse_counted_alloc(std::size_t n, std::size_t align) noexcept {
  rtfuse::test::g_total_allocations.fetch_add(1, std::memory_order_relaxed);
  if (rtfuse::test::AllocCounter::armed.load(std::memory_order_relaxed)) {
    rtfuse::test::AllocCounter::count.fetch_add(1, std::memory_order_relaxed);
  }
  void* p = nullptr;
  if (align > alignof(std::max_align_t)) {
    if (posix_memalign(&p, align, n == 0 ? 1 : n) != 0) p = nullptr;
  } else {
    p = std::malloc(n == 0 ? 1 : n);
  }
  return p;
}

static void* rtfuse_counted_alloc_or_throw(std::size_t n, std::size_t align) {
  void* p = rtfuse_counted_alloc(n, align);
  if (!p) throw std::bad_alloc();
  return p;
}

void* operator new(std::size_t n) { return rtfuse_counted_alloc_or_throw(n, 0); }
void* operator new[](std::size_t n) { return rtfuse_counted_alloc_or_throw(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) {
  return rtfuse_counted_alloc_or_throw(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return rtfuse_counted_alloc_or_throw(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return rtfuse_counted_alloc(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return rtfuse_counted_alloc(n, 0); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return rtfuse_counted_alloc(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return rtfuse_counted_alloc(n, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
