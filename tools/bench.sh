#!/usr/bin/env bash
# bench.sh [benchmark args...]: build the release tree (portable Release flags,
# no -march=native) and run rtfuse_bench with 5 repetitions, reporting the
# aggregates (mean, median, stddev, cv). Extra arguments go to the benchmark,
# e.g. tools/bench.sh --benchmark_filter=BM_Ekf
#      tools/bench.sh --benchmark_out=bench.json --benchmark_out_format=json
# The figures in docs/performance.md are the medians of this run.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

"$root/tools/setup-deps.sh"
"$root/tools/build.sh" release

bench="$root/build/release/tests/bench/rtfuse_bench"
if [[ ! -x "$bench" ]]; then
  echo "bench.sh: $bench was not built (is RTFUSE_BUILD_BENCH on in build/release?)" >&2
  exit 1
fi
exec "$bench" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true "$@"
