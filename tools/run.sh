#!/usr/bin/env bash
# Quick start, main job: install what is missing, build, and run rtfused live
# on the simulated robot (embedded config/sim.toml). Extra arguments go to
# rtfused, e.g. tools/run.sh --duration 20 or tools/run.sh --config my.toml
# With a [mapping] section (the embedded config has one) the map's files are
# left at exit in build/map.{bt,pgm,yaml,png}, unless --map-out says where.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/setup-deps.sh"
"$root/tools/build.sh" release >/dev/null
if (($# == 0)); then
  set -- --duration 60
fi
config=""
map_out=0
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  case "${args[i]}" in
    -c|--config) config=${args[i + 1]:-} ;;
    --config=*) config=${args[i]#--config=} ;;
    --map-out|--map-out=*) map_out=1 ;;
  esac
done
if ((!map_out)) && { [[ -z "$config" ]] || grep -q '^\[mapping\]' "$config" 2>/dev/null; }; then
  set -- "$@" --map-out "$root/build/map"
fi
exec "$root/build/release/src/apps/rtfused" "$@"
