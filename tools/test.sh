#!/usr/bin/env bash
# Quick start, tests: install what is missing, build the test tree, run every
# test (unit, integration, system, tools, package, deploy) with CTest; then
# the sanitizer stage (tools/sanitize.sh: ASan+UBSan over the unit and
# integration tests, TSan over the core and runtime tests and the daemon),
# with the fuzz regression (tools/fuzz.sh --regression: every harness
# replays its seeds and past findings and fuzzes briefly);
# then the aarch64 stage (tools/test-cross.sh): cross build, unit tests
# under qemu, the cross-architecture replay, the arm64 package in a clean
# arm64 root, the target-ABI check.
# CTest arguments are passed to the CTest stages (e.g. -R replay).
# RTFUSE_SANITIZERS=0 and RTFUSE_CROSS=0 skip those stages (a quicker local
# run; CI runs them all).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# Each stage's wall time is printed so the CI budget can be watched
# (docs/performance.md, "CI budget").
stage() {
  local start=$SECONDS
  "$@"
  echo "test.sh: stage '$*' took $((SECONDS - start)) s" >&2
}
cross=1
[[ "${RTFUSE_CROSS:-1}" != 0 ]] || cross=0
stage "$root/tools/setup-deps.sh"
# The Debian roots and the sysroot the package, deploy and aarch64 stages
# reuse are mostly downloads and unpacking: made beside the native build,
# which has the CPU, and waited for before any test runs, so no test shares
# its cores with them.
mkdir -p "$root/build"
"$root/tools/warm-caches.sh" $( ((cross)) || echo --no-cross) >"$root/build/warm-caches.log" 2>&1 &
warm=$!
stage "$root/tools/build.sh" test
warm_start=$SECONDS
wait "$warm" || true
cat "$root/build/warm-caches.log" >&2
echo "test.sh: stage 'waiting for tools/warm-caches.sh' took $((SECONDS - warm_start)) s" >&2
(cd "$root/build/test" && stage ctest --output-on-failure -j2 "$@")
if [[ "${RTFUSE_SANITIZERS:-1}" != 0 ]]; then
  stage "$root/tools/sanitize.sh" asan "$@"
  stage "$root/tools/fuzz.sh" --regression
  stage "$root/tools/sanitize.sh" tsan
fi
if ((cross)); then
  stage "$root/tools/test-cross.sh" "$@"
fi
