#!/usr/bin/env bash
# bench-emulated.sh [FILTER]: the EKF and loop benchmarks of the aarch64 build
# under qemu-aarch64, next to the same benchmarks of the native build, run
# back to back, as a markdown table with the emulated/native ratio.
#
# The emulated figures are qemu's, not a TX2's: user-mode emulation
# translates every aarch64 instruction, so only the ratio on the same
# machine and run means anything, and only as a sign of how the code paths
# compare. Both trees are the test builds tools/test.sh and
# tools/test-cross.sh make (-O2 -g, assertions on): same flags on both sides.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
filter=${1:-'BM_Ekf|BM_LoopTick|BM_HardwareTick'}
native="$root/build/test/tests/bench/rtfuse_bench"
cross="$root/build/aarch64/tests/bench/rtfuse_bench"
sysroot="$root/build/sysroot-arm64"
for b in "$native" "$cross"; do
  [[ -x $b ]] || { echo "bench-emulated: $b missing: run tools/test.sh (native and aarch64 stages) first" >&2; exit 2; }
done
qemu=$(command -v qemu-aarch64 || command -v qemu-aarch64-static) ||
  { echo "bench-emulated: qemu-aarch64 not found (apt-get install qemu-user)" >&2; exit 2; }

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
args=(--benchmark_filter="$filter" --benchmark_min_time=0.5 --benchmark_format=json)
"$native" "${args[@]}" >"$out/native.json"
"$qemu" -L "$sysroot" "$cross" "${args[@]}" >"$out/emulated.json"

/usr/bin/python3 - "$out/native.json" "$out/emulated.json" <<'EOF'
import json, sys
native, emulated = (json.load(open(p)) for p in sys.argv[1:3])
em = {b["name"]: b for b in emulated["benchmarks"]}
print(f"native: {native['context']['host_name']}, {native['context']['num_cpus']} CPUs; "
      f"emulated: qemu-aarch64 on the same machine")
print("| benchmark | native x86-64 | aarch64 under qemu | ratio |")
print("|---|---|---|---|")
for b in native["benchmarks"]:
    e = em.get(b["name"])
    if not e or b.get("error_occurred") or e.get("error_occurred"):
        print(f"| `{b['name']}` | error or missing | | |")
        continue
    unit = b["time_unit"]
    print(f"| `{b['name']}` | {b['real_time']:.0f} {unit} | {e['real_time']:.0f} {unit} | "
          f"{e['real_time'] / b['real_time']:.1f}x |")
EOF
