#!/usr/bin/env bash
# fuzz.sh [--time SECONDS] [--runs N] [--jobs J] [--regression] [HARNESS...]
#
# Builds the libFuzzer harnesses (tests/fuzz, clang with ASan+UBSan, in the
# sanitizer tree build/asan: tools/asan_tree.sh), seeds them, and runs each one (all of them without a name):
#   --time S      stop each harness after S seconds (default 600);
#   --runs N      ... or after N executions, whichever comes first;
#   --jobs J      harnesses run side by side (default: the CPU count);
#   --regression  the test command's short run: each harness replays its
#                 seeds and regression inputs and fuzzes for
#                 RTFUSE_FUZZ_SECONDS (default 20) seconds.
# Seeds (build/asan/seeds/<harness>, remade every run): the repository's own
# configs and calibration file, the KITTI calib.txt and poses.txt of the
# shared data, what tests/fuzz/make_seeds encodes (a HAL recording, its
# records, LCM input messages), and tests/fuzz/regressions/<harness>.
# The corpus a run grows is kept in build/asan/corpus/<harness> for the next.
# A finding (crash, UB, leak, failed property, timeout, out of memory) is
# saved in build/asan/findings/<harness>/ and makes the exit status 1.
# Each harness's figures (executions, coverage, corpus) are printed and
# written to build/asan/report.txt (docs/reliability.md, "Fuzzing").
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
time=600 runs=0 jobs=$(nproc) regression=0
harnesses=()
while (($#)); do
  case "$1" in
    --time) time=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --regression) regression=1; time=${RTFUSE_FUZZ_SECONDS:-20}; shift ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
all=(config event_log hal_recording hal_record_codec sample_decoder canopen mpu zed_calibration kitti daemon_input)
((${#harnesses[@]})) || harnesses=("${all[@]}")

"$root/tools/setup-deps.sh"
# shellcheck source=asan_tree.sh
source "$root/tools/asan_tree.sh"
configure_asan_tree
dir="$asan_tree"
cmake --build "$dir" -j"$(nproc)" --target rtfuse_fuzzers
data=$(sed -n 's/^RTFUSE_SHARED_DATA:PATH=//p' "$dir/CMakeCache.txt")

# --- seeds ----------------------------------------------------------------
seeds="$dir/seeds"
rm -rf "$seeds"
for h in "${all[@]}"; do mkdir -p "$seeds/$h" "$dir/corpus/$h" "$dir/findings/$h"; done
cp "$root"/config/*.toml "$root"/config/scenarios/*.toml "$seeds/config/"
for f in "$root"/config/calibration/*.conf; do
  for r in 0 1 2 3; do  # the harness's first byte: 2K, FHD, HD, VGA
    { printf "\\x0$r"; cat "$f"; } >"$seeds/zed_calibration/r$r-$(basename "$f")"
  done
done
if [[ -d "$data/kitti" ]]; then
  n=0
  for d in "$data"/kitti/*/; do
    n=$((n + 1))
    [[ -f "$d/calib.txt" ]] && { printf '\x01'; cat "$d/calib.txt"; } >"$seeds/kitti/calib$n"
    [[ -f "$d/poses.txt" ]] && { printf '\x00'; head -n 20 "$d/poses.txt"; } >"$seeds/kitti/poses$n"
  done
fi
"$dir/tests/fuzz/make_seeds" "$seeds" >/dev/null
for h in "${all[@]}"; do
  [[ -d "$root/tests/fuzz/regressions/$h" ]] && cp "$root/tests/fuzz/regressions/$h"/* "$seeds/$h/"
done
# The daemon's input path takes the decoders' messages, with their selector.
cp "$seeds/sample_decoder"/* "$seeds/daemon_input/"

# --- runs -----------------------------------------------------------------
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
run_one() {  # harness
  local h=$1 log="$dir/findings/$1/run.log"
  local args=(-max_total_time="$time" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
              -artifact_prefix="$dir/findings/$h/")
  ((runs > 0)) && args+=(-runs="$runs")
  local start=$SECONDS rc=0
  "$dir/tests/fuzz/${h}_fuzz" "${args[@]}" "$dir/corpus/$h" "$seeds/$h" >"$log" 2>&1 || rc=$?
  local execs cov ft corpus rate
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -ao 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  ft=$(grep -ao 'ft: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  corpus=$(find "$dir/corpus/$h" -type f | wc -l)
  local verdict=clean
  if ((rc != 0)); then
    verdict="FINDING (exit $rc): $(grep -a -m1 -E "ERROR:|runtime error|property failed|Assertion|^${h}_fuzz:" "$log" ||
      echo 'see log'); log $log"
  fi
  # A harness's own figures (daemon_input: messages, outputs checked, ticks).
  local own
  own=$(grep -a "^${h}_fuzz: .*published" "$log" | tail -1 | sed "s/^${h}_fuzz: //")
  if [[ -n "$own" ]]; then verdict+=" ($own)"; fi
  printf '%-17s %12s execs %8s/s  cov %5s  ft %6s  corpus %5s  %4ss  %s\n' \
    "$h" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "$corpus" "$((SECONDS - start))" "$verdict"
  ((rc == 0))
}
export -f run_one
export dir seeds time runs
report="$dir/report.txt"
echo "fuzz.sh: ${#harnesses[@]} harnesses, ${time} s each$( ((runs > 0)) && echo " or $runs runs"), $jobs at a time"
status=0
printf '%s\n' "${harnesses[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one {}' | tee "$report" || status=1
if ((status != 0)); then
  echo "fuzz.sh: findings: see build/asan/findings/<harness>/ (reproduce: build/asan/tests/fuzz/<harness>_fuzz FILE)" >&2
  exit 1
fi
echo "fuzz.sh: no finding"
