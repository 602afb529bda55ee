#!/usr/bin/env bash
# build.sh release|test [extra cmake args]: configure (once) and build a tree
# under build/. The test tree keeps assertions on and arms Eigen's allocation
# check; the release tree uses the portable flags a deployed build uses.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-release}
shift || true

case "$kind" in
  release)
    args=(-DCMAKE_BUILD_TYPE=Release -DRTFUSE_BUILD_TESTS=OFF -DRTFUSE_BUILD_BENCH=ON) ;;
  test)
    args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g"
          -DRTFUSE_BUILD_TESTS=ON -DRTFUSE_EIGEN_NO_MALLOC_CHECK=ON -DRTFUSE_WERROR=ON) ;;
  *) echo "usage: build.sh release|test" >&2; exit 2 ;;
esac

dir="$root/build/$kind"
if [[ ! -f "$dir/build.ninja" ]]; then
  cmake -S "$root" -B "$dir" -G Ninja "${args[@]}" "$@"
fi
cmake --build "$dir" -j"$(nproc)"
