#!/usr/bin/env bash
# Quick start, tests: install what is missing, build the test tree, run every
# test (unit, integration, system, tools, package, deploy) with CTest; then
# the aarch64 stage (tools/test-cross.sh): cross build, tests under qemu, the
# arm64 package in a clean arm64 root, the target-ABI check.
# CTest arguments are passed to both stages (e.g. -R replay).
# RTFUSE_CROSS=0 skips the aarch64 stage (a quicker local run; CI runs both).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup-deps.sh"
"$root/tools/build.sh" test
(cd "$root/build/test" && ctest --output-on-failure -j2 "$@")
if [[ "${RTFUSE_CROSS:-1}" != 0 ]]; then
  "$root/tools/test-cross.sh" "$@"
fi
