# Sourced by tools/sanitize.sh and tools/fuzz.sh: the one AddressSanitizer
# tree both use, build/asan. clang, ASan+UBSan (-O1 -g1, no recovery), the
# unit and integration tests, and the libFuzzer harnesses: every library
# carries libFuzzer's coverage instrumentation, so one build serves the
# sanitized tests and the fuzzers (clang also builds it faster than GCC).
asan_tree="$root/build/asan"
configure_asan_tree() {
  # A tree made by an older sanitize.sh (GCC, no harnesses) is made anew.
  if [[ -f "$asan_tree/CMakeCache.txt" ]] && ! grep -q '^RTFUSE_BUILD_FUZZ:BOOL=ON' "$asan_tree/CMakeCache.txt"; then
    rm -rf "$asan_tree"
  fi
  if [[ ! -f "$asan_tree/build.ninja" ]]; then
    cmake -S "$root" -B "$asan_tree" -G Ninja -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
      -DRTFUSE_BUILD_TESTS=ON -DRTFUSE_BUILD_BENCH=OFF -DRTFUSE_BUILD_FUZZ=ON -DRTFUSE_WERROR=ON \
      -DRTFUSE_EIGEN_NO_MALLOC_CHECK=ON -DRTFUSE_SANITIZE=address,undefined >/dev/null
  fi
}
