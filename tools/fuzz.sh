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
#                 RTFUSE_FUZZ_SECONDS (default 10) seconds.
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
    --regression) regression=1; time=${RTFUSE_FUZZ_SECONDS:-10}; shift ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
all=(config event_log hal_recording hal_record_codec sample_decoder canopen mpu zed_calibration kitti gnss point_cloud map_server octomap_binary daemon_input nav_command)
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
# OctoMap's real scan, its first lines (a cloud of a few hundred points).
if [[ -f "$data/octomap/scan.dat.bz2" ]]; then
  { bzip2 -dc "$data/octomap/scan.dat.bz2" || true; } | head -n 300 >"$seeds/point_cloud/scan300.xyz"
fi
# .bt files: one occupied voxel (a path of inner nodes), a coarse free
# leaf; and OctoMap's own example map where Debian installs it.
{ printf '# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.1\ndata\n\x00\xc0'
  for _ in $(seq 14); do printf '\x03\x00'; done; printf '\x02\x00'; } >"$seeds/octomap_binary/voxel.bt"
{ printf '# Octomap OcTree binary file\nid OcTree\nsize 11\nres 0.1\ndata\n\x00\xc0'
  for _ in $(seq 8); do printf '\x03\x00'; done; printf '\x01\x00'; } >"$seeds/octomap_binary/coarse.bt"
printf '# a comment, a blank line, signs and exponents\n\n+1.5 -2e-1 0.25\n 3 4 5 \n' >"$seeds/point_cloud/small.xyz"
# rtfuse-plan's inputs: a YAML as the mapper writes it (first byte 1), a
# binary and a plain PGM (0), start/goal pairs (2).
printf '\x01image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-10, -10, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n' >"$seeds/map_server/map.yaml"
printf '\x00P5\n3 2\n255\n\x00\xfe\xcd\xcd\xfe\x00' >"$seeds/map_server/binary.pgm"
printf '\x00P2\n# comment\n2 2\n255\n0 254\n205 100\n' >"$seeds/map_server/plain.pgm"
printf '\x02# sx sy gx gy\n10 10 300 250\n\n+3 4 5 -6\n' >"$seeds/map_server/pairs.txt"
"$dir/tests/fuzz/make_seeds" "$seeds" >/dev/null
for h in "${all[@]}"; do
  [[ -d "$root/tests/fuzz/regressions/$h" ]] && cp "$root/tests/fuzz/regressions/$h"/* "$seeds/$h/"
done
# A receiver's output: NMEA epochs (GGA, RMC, GSA, GST) and UBX NAV-PVT
# frames, alone and interleaved; the first byte is the harness's selector.
/usr/bin/python3 - "$seeds/gnss" <<'PY'
import functools, struct, sys
def nmea(body):
    return ("$%s*%02X\r\n" % (body, functools.reduce(lambda a, c: a ^ ord(c), body, 0))).encode()
def ubx(cls, mid, payload):
    body = bytes([cls, mid]) + struct.pack("<H", len(payload)) + payload
    a = b = 0
    for x in body:
        a = (a + x) & 0xFF
        b = (b + a) & 0xFF
    return b"\xb5\x62" + body + bytes([a, b])
def pvt(fix_type, flags):
    p = bytearray(92)
    struct.pack_into("<IHBBBBBBIiBBBBiiiiIIiiiiiIIH", p, 0, 45319200, 2026, 11, 26, 12, 35, 19, 7, 50, 200000000,
                     fix_type, flags, 0, 12, 115166667, 481173000, 592300, 545400, 1500, 2500, 1000, -500, 200,
                     1118, 9000000, 300, 1000000, 130)
    return ubx(1, 7, bytes(p))
epoch = b"".join(nmea(s) for s in (
    "GPRMC,123519.00,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W,A",
    "GPGGA,123519.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,",
    "GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1",
    "GPGST,123519.00,0.006,0.023,0.020,273.6,0.023,0.020,0.031"))
nofix = nmea("GPGGA,123520.00,,,,,0,00,99.99,,,,,,") + nmea("GPRMC,123520.00,V,,,,,,,230394,,,N")
frames = b"".join(pvt(t, f) for t, f in ((3, 1), (2, 3), (4, 0x81), (1, 0), (3, 0)))
for sel in range(4):
    open(f"{sys.argv[1]}/nmea{sel}", "wb").write(bytes([sel]) + epoch + nofix)
open(f"{sys.argv[1]}/ubx", "wb").write(b"\x00" + frames)
open(f"{sys.argv[1]}/mixed", "wb").write(b"\x03" + pvt(3, 1) + epoch + pvt(3, 1) + nofix)
PY
# The path follower and its gate (tests/fuzz/nav_command_fuzz.cpp has the
# format): a drive along an L on a free map at 20 Hz, and one where the map
# blocks the path, the stamps jump and the commands are NaN, infinite, huge.
/usr/bin/python3 - "$seeds/nav_command" <<'PY'
import struct, sys
def small(v):  # even tag: int16 thousandths
    return b"\x00" + struct.pack("<h", round(v * 1000))
def raw(v):    # odd tag: the double's bytes
    return b"\x01" + struct.pack("<d", v)
def path(points):
    return b"\x00" + bytes([len(points)]) + b"".join(small(x) + small(y) for x, y in points)
def step(x, y, yaw, flags=0, advance=10, extra=b""):
    return b"\x01" + small(x) + small(y) + small(yaw) + bytes([flags, advance, 0, 0]) + extra
drive = b"\x00" + bytes(8) + path([(-1.5, -1.5), (1.0, -1.5), (1.0, 1.5)])
drive += b"".join(step(-1.5 + 0.025 * k, -1.5, 0.0) for k in range(100))
drive += b"".join(step(1.0, -1.5 + 0.025 * k, 1.57) for k in range(120))
open(f"{sys.argv[1]}/drive", "wb").write(drive)
rough = b"\x02" + bytes([0, 0, 0, 0x18, 0x18, 0, 0, 0]) + path([(-1.8, 0.1), (1.8, 0.1)])
rough += b"".join(step(-1.8 + 0.01 * k, 0.1, 0.0) for k in range(30))
rough += step(0.0, 0.1, 0.0, 0x10, 10, raw(float("nan")) + raw(1.0))
rough += step(0.0, 0.1, 0.0, 0x18, 10, raw(1e308) + raw(float("inf")) + raw(-1e308))
rough += b"\x01" + raw(float("nan")) + small(0.0) + small(0.0) + bytes([0x20]) + struct.pack("<q", 2**63 - 1) + bytes([0, 0])
rough += b"\x00\x03" + raw(0.0) + raw(0.0) + raw(float("inf")) + raw(1.0) + raw(5e-324) + raw(1e300)
rough += b"".join(step(-1.0, 0.1, 3.0, 0x80, 10, raw(-2.0) + raw(-2.0) + raw(5e-324)) for _ in range(3))
open(f"{sys.argv[1]}/rough", "wb").write(rough)
PY
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
