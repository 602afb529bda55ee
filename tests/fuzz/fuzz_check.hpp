#pragma once
// A property a harness asserts on every input: when it fails, the input is a
// finding like a crash (abort, so libFuzzer saves it as crash-<sha1>).
#include <cstdio>
#include <cstdlib>

#define FUZZ_CHECK(cond, what)                                                                \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      std::fprintf(stderr, "%s:%d: property failed: %s (%s)\n", __FILE__, __LINE__, #cond, what); \
      std::abort();                                                                           \
    }                                                                                         \
  } while (0)
