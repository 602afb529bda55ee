#!/usr/bin/env bash
# run_system_test.sh MODE OUTDIR RTFUSED [NAME=VALUE]...
#
# The system tests: the real rtfused and real LCM tools as separate processes
# over real UDP multicast, inside a private network namespace so that no
# packet ever leaves it (multicast is routed to lo and the URL has ttl=0).
#
#   udp_multicast  lcm-logger records ~5 s of rtfused's outputs; check_system.py
#                  checks channels, counts, rates (the mapper's grid at 1 Hz
#                  included), rtfused's exit and summary
#   jvm_decode     the same recording, then every rtfuse/* event decoded by the
#                  JVM with the generated classes, as lcm-spy would (plus two
#                  damaged copies of the log that must be rejected)
#   zero_alloc     rtfused --record under LD_PRELOAD=alloc_probe: no heap allocation in
#                  steady state, in any thread (after the probe's self-test)
#   live_soak      rtfused on the simulated robot with every sensor at a 1 kHz loop
#                  for SOAK_SECONDS (120) under the probe: nothing allocated in steady
#                  state, resident memory flat after a 20 s warm-up (sampled every
#                  5 s, growth <= 64 KiB), overruns counted and reported
#   cpu_hog        rtfused with every thread on one CPU and two busy processes at nice
#                  -20 on it for 5 s, twice: every thread under SCHED_OTHER (starved), and
#                  under SCHED_FIFO ([realtime] priority = 80, io_priority = 70, lock_memory); lcm-logger records the
#                  diagnostics at 20 Hz, the odometry and the ground truth, and
#                  check_cpu_hog.py (HOG_CHECK) measures what is reported, when, and
#                  the estimate meanwhile
#   disk_full      rtfused --record onto a 1 MiB tmpfs (a private mount namespace):
#                  the loop runs on to --duration, the write error is named at exit
#                  (exit 1), and the cut recording replays with --allow-truncated
#                  (REPLAY) and is refused without it
#
# NAME=VALUE settings (passed by tests/system/CMakeLists.txt):
#   PYTHON CHECK HOG_CHECK TOOLS_DIR JAVA CLASSPATH_DECODE PROBE PROBE_SELFTEST CONFIG_DIR SOAK_SECONDS
#
# Exit: 0 pass, 1 fail, 77 skipped (no network namespace and
# RTFUSE_SKIP_NETNS=1, or no JVM for jvm_decode).
set -euo pipefail

SKIP=77
URL='udpm://239.255.76.67:7667?ttl=0'
# The logger's socket gets a receive buffer that holds whole grids:
# config/sim_nav.toml's 24 m grid is a 230 kB message, larger than the
# kernel's default 208 kB (rmem_default), so under load the logger lost
# fragments and with them whole grids (LCM warns "receive buffer is very
# small"). The kernel caps the request at net.core.rmem_max.
LOGGER_URL="$URL&recv_buf_size=4194304"

if [[ $# -lt 3 ]]; then
  echo "usage: $0 udp_multicast|jvm_decode|zero_alloc OUTDIR RTFUSED [NAME=VALUE]..." >&2
  exit 2
fi
mode=$1 outdir=$2 rtfused=$3
shift 3
PYTHON=/usr/bin/python3 CHECK= HOG_CHECK= TOOLS_DIR= JAVA= CLASSPATH_DECODE= PROBE= PROBE_SELFTEST= CONFIG_DIR= SOAK_SECONDS=120 REPLAY=
for kv in "$@"; do
  case "$kv" in
    PYTHON=* | CHECK=* | HOG_CHECK=* | TOOLS_DIR=* | JAVA=* | CLASSPATH_DECODE=* | PROBE=* | PROBE_SELFTEST=* | CONFIG_DIR=* | SOAK_SECONDS=* | REPLAY=*)
      printf -v "${kv%%=*}" '%s' "${kv#*=}" ;;
    *) echo "$0: unknown setting '$kv'" >&2; exit 2 ;;
  esac
done
case "$mode" in udp_multicast | jvm_decode | zero_alloc | live_soak | cpu_hog | disk_full) ;; *) echo "$0: unknown mode '$mode'" >&2; exit 2 ;; esac

say() { echo "[$mode] $*"; }
die() { echo "[$mode] FAIL: $*"; exit 1; }

# ---------------------------------------------------------------------------
# Outside the namespace: check the prerequisites, then re-run this script
# under unshare -n.
if [[ "${RTFUSE_SYSTEM_TEST_IN_NETNS:-}" != "1" ]]; then
  [[ -x "$rtfused" ]] || die "rtfused not found or not executable: $rtfused"
  if [[ "$mode" == jvm_decode && ( -z "$JAVA" || ! -x "$JAVA" || -z "$CLASSPATH_DECODE" ) ]]; then
    echo "[$mode] SKIP: no JVM or no rtfuse_lcmtypes.jar (javac/jar/lcm.jar missing at configure time)"
    exit $SKIP
  fi
  unshare_cmd=(unshare -n)
  if ! err=$(unshare -n true 2>&1); then
    # Not root: a user namespace gives the same isolation where it is allowed.
    if [[ $(id -u) -ne 0 ]] && unshare -r -n true 2>/dev/null; then
      unshare_cmd=(unshare -r -n)
      say "unshare -n refused ($err); using a user namespace (unshare -r -n)"
    elif [[ "${RTFUSE_SKIP_NETNS:-}" == "1" ]]; then
      echo "[$mode] SKIP: cannot create a private network namespace (unshare -n: $err); RTFUSE_SKIP_NETNS=1"
      exit $SKIP
    else
      die "cannot create a private network namespace: 'unshare -n true' failed: $err
  The system tests send real UDP multicast and must never do it on the host's
  network. Run them as root (or in a container with CAP_SYS_ADMIN), or set
  RTFUSE_SKIP_NETNS=1 to skip them."
    fi
  fi
  rm -rf "$outdir"
  mkdir -p "$outdir"
  RTFUSE_SYSTEM_TEST_IN_NETNS=1 exec "${unshare_cmd[@]}" -- "$BASH" "$0" "$mode" "$outdir" "$rtfused" \
    PYTHON="$PYTHON" CHECK="$CHECK" HOG_CHECK="$HOG_CHECK" TOOLS_DIR="$TOOLS_DIR" JAVA="$JAVA" CLASSPATH_DECODE="$CLASSPATH_DECODE" \
    PROBE="$PROBE" PROBE_SELFTEST="$PROBE_SELFTEST" CONFIG_DIR="$CONFIG_DIR" SOAK_SECONDS="$SOAK_SECONDS" REPLAY="$REPLAY"
fi

# ---------------------------------------------------------------------------
# Inside the private network namespace.
pids=()
cleanup() {
  local p
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

ip link set lo up || die "ip link set lo up failed"
ip route replace 224.0.0.0/4 dev lo || die "ip route replace 224.0.0.0/4 dev lo failed"
# Safety: this namespace must hold nothing but lo, so nothing can leave it.
links=$(ip -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
[[ "$links" == "lo " ]] || die "not a private network namespace (links: $links); refusing to send multicast"
say "private network namespace: links [${links% }], route $(ip route show 224.0.0.0/4)"

export RTFUSE_TOOLS_DIR="$TOOLS_DIR"

show() { # show FILE TITLE: a file's content, indented, for the CTest log
  [[ -s "$1" ]] || return 0
  echo "--- $2 ---"
  sed 's/^/  /' "$1"
}

# record LOG: lcm-logger for ~5 s while rtfused runs 6 s (with the
# arguments in rtfused_args); sets rtfused_rc
rtfused_args=()
record() {
  local log=$1
  command -v lcm-logger >/dev/null || die "lcm-logger not found (package liblcm-bin)"
  lcm-logger -q -f --lcm-url="$LOGGER_URL" "$log" >"$outdir/lcm-logger.out" 2>&1 &
  local logger=$!
  pids+=("$logger")
  sleep 0.5
  kill -0 "$logger" 2>/dev/null || { show "$outdir/lcm-logger.out" lcm-logger; die "lcm-logger did not start"; }

  timeout -k 5 25 "$rtfused" --duration 6 --lcm-url "$URL" "${rtfused_args[@]}" \
    >"$outdir/rtfused.stdout" 2>"$outdir/rtfused.stderr" &
  local daemon=$!
  pids+=("$daemon")
  sleep 5
  kill -INT "$logger" 2>/dev/null || true
  local logger_rc=0
  wait "$logger" || logger_rc=$?
  rtfused_rc=0
  wait "$daemon" || rtfused_rc=$?
  show "$outdir/rtfused.stderr" "rtfused stderr"
  show "$outdir/rtfused.stdout" "rtfused stdout"
  show "$outdir/lcm-logger.out" "lcm-logger"
  say "rtfused exit status $rtfused_rc, lcm-logger exit status $logger_rc"
  [[ $rtfused_rc -ne 124 && $rtfused_rc -ne 137 ]] || die "rtfused --duration 6 did not stop within 25 s"
  [[ -f "$log" ]] || die "lcm-logger wrote no log"
}

# The grid's rate: 1 Hz of capture time, measured over the three or four
# grids of a 5 s log (wider with the navigator: config/sim_nav.toml's grid
# is 24 m across and its mapper shares two cores with the planner).
map_rate=0.7:1.3
check_log() {
  "$PYTHON" "$CHECK" log "$1" --rtfused-rc "$rtfused_rc" --rtfused-stdout "$outdir/rtfused.stdout" \
    --expect rtfuse/odometry:101 --expect rtfuse/pose:101 --expect rtfuse/tf:101 \
    --expect rtfuse/state:21 --expect rtfuse/diagnostics:3 --expect rtfuse/map:3 \
    --rate rtfuse/odometry:35:65 --rate rtfuse/pose:35:65 --rate rtfuse/tf:35:65 --rate rtfuse/state:7:13 \
    --rate "rtfuse/map:$map_rate"
}

case "$mode" in
  udp_multicast)
    record "$outdir/udp_multicast.lcm"
    check_log "$outdir/udp_multicast.lcm" || die "the recording over UDP multicast failed its checks"
    ;;

  jvm_decode)
    # The robot that drives itself (config/sim_nav.toml): its first goal at
    # 3 s, so the log also holds a path, commands and the navigator's status.
    [[ -f "$CONFIG_DIR/sim_nav.toml" ]] || die "no config/sim_nav.toml under CONFIG_DIR=$CONFIG_DIR"
    rtfused_args=(--config "$CONFIG_DIR/sim_nav.toml")
    map_rate=0.4:1.3
    record "$outdir/jvm_decode.lcm"
    check_log "$outdir/jvm_decode.lcm" >"$outdir/check_log.out" 2>&1 || {
      cat "$outdir/check_log.out"
      die "the recording failed its checks; nothing to decode"
    }
    expect=(rtfuse/odometry=rtfuse.odometry_t:101
            rtfuse/pose=rtfuse.pose_with_covariance_stamped_t:101
            rtfuse/tf=rtfuse.tf_t:101
            rtfuse/state=rtfuse.filter_state_t:21
            rtfuse/diagnostics=rtfuse.diagnostics_t:3
            rtfuse/map=rtfuse.occupancy_grid_t:3
            rtfuse/path=rtfuse.path_t:1
            rtfuse/cmd_vel=rtfuse.twist_stamped_t:50
            rtfuse/nav_status=rtfuse.nav_status_t:50)
    decode() { CLASSPATH= "$JAVA" -Djava.awt.headless=true -cp "$CLASSPATH_DECODE" DecodeAll "$@"; }
    say "decoding every rtfuse/* event with the generated Java classes"
    decode "$outdir/jvm_decode.lcm" "${expect[@]}" || die "the JVM could not decode the log"
    # Negative controls: the decoder must reject a damaged log.
    for kind in fingerprint truncate; do
      "$PYTHON" "$CHECK" corrupt "$outdir/jvm_decode.lcm" "$outdir/damaged-$kind.lcm" "$kind" >/dev/null ||
        die "cannot write the damaged log ($kind)"
      if decode "$outdir/damaged-$kind.lcm" "${expect[@]}" >"$outdir/damaged-$kind.out" 2>&1; then
        cat "$outdir/damaged-$kind.out"
        die "DecodeAll accepted a log with a damaged event ($kind)"
      fi
      say "negative control ($kind): rejected: $(grep -m1 '^ERROR' "$outdir/damaged-$kind.out" || true)"
    done
    ;;

  zero_alloc)
    [[ -f "$PROBE" ]] || die "alloc probe not found: $PROBE"
    say "probe self-test: a known allocation pattern must be seen"
    if ! RTFUSE_ALLOC_REPORT="$outdir/selftest.report" LD_PRELOAD="$PROBE" timeout 20 "$PROBE_SELFTEST" ||
       ! "$PYTHON" "$CHECK" alloc "$outdir/selftest.report" --selftest >"$outdir/selftest.out" 2>&1; then
      show "$outdir/selftest.out" "self-test"
      show "$outdir/selftest.report" "self-test report"
      die "the allocation probe's self-test failed: its verdict on rtfused would mean nothing"
    fi
    say "probe self-test OK"
    rc=0
    RTFUSE_ALLOC_REPORT="$outdir/rtfused.report" LD_PRELOAD="$PROBE" \
      timeout -k 5 25 "$rtfused" --duration 5 --quiet --record "$outdir/recording.lcm" \
      >"$outdir/rtfused.stdout" 2>"$outdir/rtfused.stderr" || rc=$?
    show "$outdir/rtfused.stderr" "rtfused stderr"
    show "$outdir/rtfused.stdout" "rtfused stdout"
    say "rtfused exit status $rc"
    "$PYTHON" "$CHECK" alloc "$outdir/rtfused.report" --rtfused-stdout "$outdir/rtfused.stdout" || {
      echo "(raw report: $outdir/rtfused.report)"
      die "rtfused allocates on the heap in steady state"
    }
    [[ $rc -eq 0 ]] || die "rtfused under the allocation probe exited with status $rc"
    ;;
  cpu_hog)
    [[ -f "$HOG_CHECK" ]] || die "check_cpu_hog.py not found: $HOG_CHECK"
    [[ -f "$CONFIG_DIR/sim.toml" ]] || die "no config/sim.toml under CONFIG_DIR=$CONFIG_DIR"
    command -v lcm-logger >/dev/null || die "lcm-logger not found (package liblcm-bin)"
    command -v taskset >/dev/null || die "taskset not found (package util-linux)"
    command -v chrt >/dev/null || die "chrt not found (package util-linux)"
    cp -r "$CONFIG_DIR" "$outdir/config"
    # The CPU everything runs on: the last this process may use (the suite's
    # other tests are not pinned, so they drift to the rest).
    cpu=$(taskset -cp $$ | sed -E 's/.*: *//; s/.*[,-]//')
    # CLOCK_REALTIME and CLOCK_MONOTONIC in µs, and the time the hypervisor
    # took from that CPU (/proc/stat "steal", ms): in a VM no priority
    # protects the loop from a host that runs something else on its core.
    stamp_with_steal() {
      "$PYTHON" -c 'import os, sys, time
cpu = "cpu" + sys.argv[1]
steal = next(int(l.split()[8]) for l in open("/proc/stat") if l.split()[0] == cpu)
print(time.time_ns() // 1000, time.monotonic_ns() // 1000, steal * 1000 // os.sysconf("SC_CLK_TCK"))' "$1"
    }
    # The protected run is configured as config/robot_linux.toml deploys:
    # SCHED_FIFO and mlockall, so that no page fault (text pages the
    # suite's builds push out of the page cache) stalls the loop.
    for run in starved:0:0:false protected:80:70:true; do
      IFS=: read -r name priority io lock <<<"$run"
      dir="$outdir/$name"
      mkdir -p "$dir"
      cfg="$outdir/config/hog_$name.toml"
      # Without the mapper: what is measured is the loop and the threads it
      # depends on; the mapper yields to all of them by design, and its
      # second-by-second grid (160 kB of multicast the logger must take in
      # to filter) would only add noise to the instrument.
      sed -E -e 's/^diagnostics_rate = [0-9.]+/diagnostics_rate = 20/' \
        -e '/^\[mapping\]/,/^\[/{/^\[mapping\]/d;/^\[/!d}' "$CONFIG_DIR/sim.toml" >"$cfg"
      grep -q '^diagnostics_rate = 20' "$cfg" || die "could not set diagnostics_rate in $cfg"
      ! grep -q '^\[mapping\]' "$cfg" || die "could not take [mapping] out of $cfg"
      printf '\n[realtime]\nlock_memory = %s\npriority = %s\nio_priority = %s\nrequire = true\n' \
        "$lock" "$priority" "$io" >>"$cfg"
      # The logger is the instrument, not the system under test: SCHED_FIFO
      # (below rtfused's threads) so that other load on the machine (a build
      # beside the suite) cannot make it drop the multicast it measures by
      # (LCM filters channels after receiving the whole group, camera
      # previews included).
      chrt -f 60 lcm-logger -q -f --lcm-url="$URL" --channel='rtfuse/diagnostics|rtfuse/odometry|sim/ground_truth' \
        "$dir/run.lcm" >"$dir/lcm-logger.out" 2>&1 &
      logger=$!
      pids+=("$logger")
      sleep 0.5
      # Every thread of rtfused on one CPU: a single-core board, or a hog on
      # the loop's core of a bigger one.
      timeout -k 5 40 taskset -c "$cpu" "$rtfused" --config "$cfg" --duration 12 --quiet --lcm-url "$URL" \
        >"$dir/rtfused.stdout" 2>"$dir/rtfused.stderr" &
      daemon=$!
      pids+=("$daemon")
      sleep 4
      hogs=()
      for _ in 1 2; do
        taskset -c "$cpu" nice -n -20 "$BASH" -c 'while :; do :; done' &
        hogs+=($!)
        pids+=($!)
      done
      echo "start $(stamp_with_steal "$cpu")" >"$dir/hog.txt"
      sleep 5
      kill -KILL "${hogs[@]}"
      wait "${hogs[@]}" 2>/dev/null || true
      echo "stop $(stamp_with_steal "$cpu")" >>"$dir/hog.txt"
      rc=0
      wait "$daemon" || rc=$?
      sleep 0.3
      kill -INT "$logger" 2>/dev/null || true
      wait "$logger" || true
      show "$dir/rtfused.stderr" "rtfused stderr ($name)"
      show "$dir/rtfused.stdout" "rtfused stdout ($name)"
      [[ $rc -eq 0 ]] || die "rtfused ($name, priority $priority) exited with status $rc"
    done
    "$PYTHON" "$HOG_CHECK" "$outdir/starved" "$outdir/protected" || die "the CPU hog checks failed"
    ;;
  disk_full)
    [[ -x "$REPLAY" ]] || die "rtfuse-replay not found: $REPLAY"
    # Its own mount namespace: the small tmpfs is seen by this run only.
    if [[ "${RTFUSE_DISK_FULL_IN_MNTNS:-}" != "1" ]]; then
      RTFUSE_DISK_FULL_IN_MNTNS=1 exec unshare -m -- "$BASH" "$0" "$mode" "$outdir" "$rtfused" REPLAY="$REPLAY"
    fi
    disk="$outdir/disk"
    mkdir -p "$disk"
    mount -t tmpfs -o size=1m tmpfs "$disk" || die "cannot mount a 1 MiB tmpfs on $disk"
    rc=0
    "$rtfused" --duration 4 --quiet --lcm-url memq:// --record "$disk/rec.lcm" \
      >"$outdir/rtfused.stdout" 2>"$outdir/rtfused.stderr" || rc=$?
    show "$outdir/rtfused.stderr" "rtfused stderr"
    say "rtfused exit status $rc; $(grep -m1 '^rtfused: ran ' "$outdir/rtfused.stdout" || echo 'no run summary')"
    ((rc == 1)) || die "rtfused recording onto a full disk exited $rc, expected 1"
    grep -q "recording $disk/rec.lcm: .*No space left on device" "$outdir/rtfused.stderr" ||
      die "rtfused did not name the full disk (ENOSPC) and the file"
    # Said while it ran (the service's journal), not only at exit.
    at=$(sed -nE "s|^rtfused: recording $disk/rec.lcm failed at ([0-9.]+) s: .*No space left on device.*|\1|p" \
      "$outdir/rtfused.stderr")
    [[ -n $at ]] || die "rtfused did not report the failed recording while it ran"
    awk -v t="$at" 'BEGIN { exit !(t < 3.5) }' || die "the failed recording was reported at $at s, not during the 4 s run"
    say "the full disk was reported $at s into the run"
    # The loop was not held up by the writer: ~4 s of 200 Hz ticks.
    ticks=$(sed -nE 's/^rtfused: ran .* ([0-9]+) ticks.*/\1/p' "$outdir/rtfused.stdout")
    [[ -n $ticks ]] && ((ticks >= 700)) || die "the loop ran ${ticks:-no} ticks in 4 s at 200 Hz (>= 700 expected)"
    rrc=0
    "$REPLAY" -l "$disk/rec.lcm" >"$outdir/replay.out" 2>&1 || rrc=$?
    ((rrc == 1)) && grep -q "truncated after event" "$outdir/replay.out" ||
      { cat "$outdir/replay.out"; die "rtfuse-replay of the cut recording: exit $rrc without naming the truncation"; }
    "$REPLAY" -l "$disk/rec.lcm" --allow-truncated >"$outdir/replay-allowed.out" 2>&1 ||
      { cat "$outdir/replay-allowed.out"; die "rtfuse-replay --allow-truncated failed on the cut recording"; }
    say "cut recording: $(grep -m1 -o 'truncated after event [0-9]*' "$outdir/replay.out"), replays with --allow-truncated"
    umount "$disk"
    ;;

  live_soak)
    [[ -f "$PROBE" ]] || die "alloc probe not found: $PROBE"
    [[ -f "$CONFIG_DIR/sim.toml" ]] || die "no config/sim.toml under CONFIG_DIR=$CONFIG_DIR"
    # config/sim.toml (every sensor, the camera and VO included) with a 1 kHz
    # loop; its relative paths (calibration, scenario) need the directory.
    cp -r "$CONFIG_DIR" "$outdir/config"
    sed -i -E 's/^frequency = [0-9]+/frequency = 1000/' "$outdir/config/sim.toml"
    grep -q '^frequency = 1000' "$outdir/config/sim.toml" || die "could not set the loop to 1 kHz in sim.toml"
    RTFUSE_ALLOC_REPORT="$outdir/rtfused.report" LD_PRELOAD="$PROBE" \
      "$rtfused" --config "$outdir/config/sim.toml" --duration "$SOAK_SECONDS" --quiet --lcm-url "$URL" \
      >"$outdir/rtfused.stdout" 2>"$outdir/rtfused.stderr" &
    daemon=$!
    pids+=("$daemon")
    : >"$outdir/rss.txt"
    for ((s = 0; s <= SOAK_SECONDS; s += 5)); do
      rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$daemon/status" 2>/dev/null) || break
      [[ -n $rss ]] || break
      echo "$s $rss" >>"$outdir/rss.txt"
      sleep 5
    done
    rc=0
    wait "$daemon" || rc=$?
    show "$outdir/rtfused.stderr" "rtfused stderr"
    show "$outdir/rtfused.stdout" "rtfused stdout"
    say "rtfused exit status $rc; resident memory (s KiB): $(tr '\n' ' ' <"$outdir/rss.txt")"
    [[ $rc -eq 0 ]] || die "rtfused exited with status $rc"
    "$PYTHON" "$CHECK" alloc "$outdir/rtfused.report" --rtfused-stdout "$outdir/rtfused.stdout" || {
      echo "(raw report: $outdir/rtfused.report)"
      die "rtfused allocates on the heap in steady state"
    }
    read -r warm growth samples < <(awk '$1 >= 20 { if (!n++) base = $2; if ($2 - base > g) g = $2 - base }
                                         END { print base, g + 0, n + 0 }' "$outdir/rss.txt")
    ((samples >= SOAK_SECONDS / 5 - 4)) || die "only $samples resident-memory samples after warm-up"
    say "resident memory after warm-up: $warm KiB, largest growth $growth KiB over $samples samples"
    ((growth <= 64)) || die "resident memory grew by $growth KiB after warm-up (limit 64 KiB)"
    summary=$(grep -m1 '^rtfused: ran ' "$outdir/rtfused.stdout") || die "rtfused printed no run summary"
    say "$summary"
    ticks=$(sed -E 's/.* ([0-9]+) ticks.*/\1/' <<<"$summary")
    ((ticks >= SOAK_SECONDS * 1000 / 2)) || die "only $ticks ticks in $SOAK_SECONDS s at 1 kHz: the loop fell far behind"
    ;;
esac
say "PASS"
