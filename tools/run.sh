#!/usr/bin/env bash
# Quick start, main job: install what is missing, build, and run rtfused live
# on the simulated robot (embedded config/sim.toml). Extra arguments go to
# rtfused, e.g. tools/run.sh --duration 20 or tools/run.sh --config my.toml
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup-deps.sh"
"$root/tools/build.sh" release >/dev/null
if (($# == 0)); then
  set -- --duration 60
fi
exec "$root/build/release/src/apps/rtfused" "$@"
