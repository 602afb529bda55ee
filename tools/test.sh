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

# The later stages' trees (ASan with the fuzz harnesses, TSan, aarch64)
# compile one after the other at the lowest priority while the tests run:
# a test's process still gets the CPU it asks for (nice 19 against 0 is
# about 1.5 % to 98.5 %), a build takes what the tests leave idle (their
# waits, a live run's sleeps, a board booting). Each stage waits for its
# tree, then builds it again in the foreground, which is a no-op unless the
# background build failed: then the foreground shows why.
sanitizers=1
[[ "${RTFUSE_SANITIZERS:-1}" != 0 ]] || sanitizers=0
prebuilt=$root/build/prebuilt
rm -rf "$prebuilt"
mkdir -p "$prebuilt"
# Its own process group (job control), so a failing stage can stop it whole.
set -m
(
  if ((sanitizers)); then
    nice -n 19 "$root/tools/sanitize.sh" build asan >"$prebuilt/asan.log" 2>&1; echo $? >"$prebuilt/asan"
    nice -n 19 "$root/tools/sanitize.sh" build tsan >"$prebuilt/tsan.log" 2>&1; echo $? >"$prebuilt/tsan"
  fi
  if ((cross)); then
    nice -n 19 "$root/tools/test-cross.sh" --build-only >"$prebuilt/aarch64.log" 2>&1; echo $? >"$prebuilt/aarch64"
  fi
) &
prebuild=$!
set +m
# Stops the background builds, compilers included, when a stage fails.
trap 'kill -- -"$prebuild" 2>/dev/null || true' EXIT
wait_for_tree() {  # name: until the background build of that tree ended
  local start=$SECONDS
  while [[ ! -f "$prebuilt/$1" ]] && kill -0 "$prebuild" 2>/dev/null; do sleep 2; done
  echo "test.sh: waited $((SECONDS - start)) s for the background build of the $1 tree (exit $(cat "$prebuilt/$1" 2>/dev/null || echo none))" >&2
}

(cd "$root/build/test" && stage ctest --output-on-failure -j2 "$@")
if ((sanitizers)); then
  wait_for_tree asan
  stage "$root/tools/sanitize.sh" asan "$@"
  stage "$root/tools/fuzz.sh" --regression
  wait_for_tree tsan
  stage "$root/tools/sanitize.sh" tsan
fi
if ((cross)); then
  wait_for_tree aarch64
  stage "$root/tools/test-cross.sh" "$@"
fi
