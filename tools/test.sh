#!/usr/bin/env bash
# Quick start, tests: install what is missing, build the test tree, run every
# test (unit, integration, system, tools, package, deploy) with CTest; then
# the sanitizer stage (tools/sanitize.sh: ASan+UBSan over the unit and
# integration tests, TSan over the core and runtime tests and the daemon),
# with the fuzz regression (tools/fuzz.sh --regression: every harness
# replays its seeds and past findings and fuzzes briefly);
# then the aarch64 stage (tools/test-cross.sh): cross build, tests under
# qemu, the arm64 package in a clean arm64 root, the target-ABI check.
# CTest arguments are passed to the CTest stages (e.g. -R replay).
# RTFUSE_SANITIZERS=0 and RTFUSE_CROSS=0 skip those stages (a quicker local
# run; CI runs them all).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# Each stage's wall time is printed so the CI budget can be watched.
stage() {
  local start=$SECONDS
  "$@"
  echo "test.sh: stage '$*' took $((SECONDS - start)) s" >&2
}
stage "$root/tools/setup-deps.sh"
stage "$root/tools/build.sh" test
(cd "$root/build/test" && stage ctest --output-on-failure -j2 "$@")
if [[ "${RTFUSE_SANITIZERS:-1}" != 0 ]]; then
  stage "$root/tools/sanitize.sh" asan "$@"
  stage "$root/tools/fuzz.sh" --regression
  stage "$root/tools/sanitize.sh" tsan
fi
if [[ "${RTFUSE_CROSS:-1}" != 0 ]]; then
  stage "$root/tools/test-cross.sh" "$@"
fi
