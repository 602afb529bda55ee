#!/usr/bin/env bash
# build.sh release|test [extra cmake args]: configure (once) and build a tree
# under build/. The test tree is the default configuration with assertions
# and debug info; the release tree uses the portable flags a deployed build uses.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-release}
shift || true

case "$kind" in
  release)
    args=(-DCMAKE_BUILD_TYPE=Release -DRTFUSE_BUILD_TESTS=OFF -DRTFUSE_BUILD_BENCH=ON) ;;
  test)
    # Every project option at its default (tests, benchmarks, the Eigen
    # allocation check, portable floating point): the tree CI tests is the
    # one a user gets from a plain `cmake -S . -B build`, so a file that only
    # compiles with some option set cannot pass CI. Only CMake's own settings
    # differ: assertions on, line tables for backtraces (-g1: a third less
    # compile time than full debug info; configure a tree with -g to step
    # through locals), and warnings as errors (CMake's switch, not ours).
    args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1"
          -DCMAKE_COMPILE_WARNING_AS_ERROR=ON) ;;
  *) echo "usage: build.sh release|test" >&2; exit 2 ;;
esac

dir="$root/build/$kind"
if [[ ! -f "$dir/build.ninja" ]]; then
  cmake -S "$root" -B "$dir" -G Ninja "${args[@]}" "$@"
fi
cmake --build "$dir" -j"$(nproc)"
