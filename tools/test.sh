#!/usr/bin/env bash
# Quick start, tests: install what is missing, build the test tree, run every
# test (unit, integration, system, tools) with CTest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup-deps.sh"
"$root/tools/build.sh" test
cd "$root/build/test"
ctest --output-on-failure -j2 "$@"
