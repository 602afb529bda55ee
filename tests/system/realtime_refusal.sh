#!/usr/bin/env bash
# rtfused asked for SCHED_FIFO and mlockall by a process the OS refuses them to
# (CAP_SYS_NICE and CAP_IPC_LOCK dropped, RLIMIT_RTPRIO 0, RLIMIT_MEMLOCK 64 KiB):
#  - realtime.require = false: says so once, with the errno text and the fix, and runs (exit 0);
#  - realtime.require = true: exits 3 with a clear message, before running.
# Also checks the process's threads carry their names, and that SIGINT stops it cleanly.
# memq:// keeps every message inside the process: no network needed.
set -euo pipefail
rtfused=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if ! command -v setpriv >/dev/null; then
  echo "setpriv (util-linux) missing"; exit 1
fi
drop=(setpriv --inh-caps=-all --bounding-set=-sys_nice,-ipc_lock)
if ! "${drop[@]}" true 2>/dev/null; then
  echo "SKIP: cannot drop capabilities here (not root?)"; exit 77
fi

run_case() {  # name lock priority require expected-exit expected-message...
  local name=$1 lock=$2 prio=$3 require=$4 expect=$5
  shift 5
  local cfg=$work/$name.toml
  cp "$src/config/sim.toml" "$cfg"
  [[ -d $work/scenarios ]] || cp -r "$src/config/scenarios" "$work/"  # the config's drive, relative to it
  [[ -d $work/calibration ]] || cp -r "$src/config/calibration" "$work/"  # and its camera's calibration
  printf '\n[realtime]\nlock_memory = %s\npriority = %s\nio_priority = %s\nrequire = %s\n' \
    "$lock" "$prio" "${IO_PRIORITY:-0}" "$require" >> "$cfg"
  set +e
  (ulimit -r 0; ulimit -l 64; "${drop[@]}" "$rtfused" --config "$cfg" --duration 1 --quiet --lcm-url memq://) \
    >"$work/$name.out" 2>"$work/$name.err"
  local code=$?
  set -e
  echo "--- $name: exit $code"; cat "$work/$name.err"
  [[ $code -eq $expect ]] || { echo "FAIL: $name: expected exit $expect"; exit 1; }
  for msg in "$@"; do
    [[ $(grep -c -- "$msg" "$work/$name.err") -eq 1 ]] || { echo "FAIL: $name: '$msg' not said exactly once"; exit 1; }
  done
}

# Optional: warn once per refused setting, then run.
IO_PRIORITY=40 run_case optional true 50 false 0 "SCHED_FIFO 50 refused: Operation not permitted" "mlockall failed" \
  "io_priority: SCHED_FIFO 40 for the publisher refused: Operation not permitted"
grep -q "measurements fused" "$work/optional.out" || { echo "FAIL: optional: did not run"; exit 1; }
# Required: a clear message naming the setting, exit 3, before running.
run_case required_fifo false 50 true 3 "SCHED_FIFO 50 refused: Operation not permitted" "realtime.require = true"
run_case required_lock true 0 true 3 "mlockall failed" "realtime.require = true"
for n in required_fifo required_lock; do
  ! grep -q "measurements fused" "$work/$n.out" || { echo "FAIL: $n ran although refused"; exit 1; }
done

# Granted (root): the loop at priority, every thread it depends on at
# io_priority, each under SCHED_FIFO; the simulator's own thread untouched.
cfg=$work/granted.toml
cp "$src/config/sim.toml" "$cfg"
printf '\n[realtime]\npriority = 60\nio_priority = 30\nrequire = true\n' >> "$cfg"
"$rtfused" --config "$cfg" --duration 120 --quiet --lcm-url memq:// >"$work/out_granted" 2>"$work/err_granted" &
pid=$!
wanted=(rtfuse-loop:1/60 rtfuse-pub:1/30 rtfuse-lcmin:1/30 rtfuse-imu:1/30 rtfuse-camera:1/30 rtfuse-sim:0/0)
# Start-up takes seconds under emulation, and a thread exists a moment
# before start() sets its policy: poll until every one is as wanted.
for _ in $(seq 120); do
  sleep 0.5
  policies=""
  for t in /proc/$pid/task/*; do
    comm=$(cat "$t/comm" 2>/dev/null) || continue
    # /proc/TID/stat after "(comm) ": field 40 is the real-time priority, 41 the policy (1 = SCHED_FIFO).
    read -r rtprio policy < <(sed -E 's/^.*\) //' "$t/stat" 2>/dev/null | awk '{print $38, $39}') || continue
    policies+="$comm:$policy/$rtprio "
  done
  missing=0
  for want in "${wanted[@]}"; do [[ " $policies " == *" $want "* ]] || missing=1; done
  ((missing == 0)) && break
done
kill -INT $pid
wait $pid || true
echo "granted: $policies"
for want in "${wanted[@]}"; do
  [[ " $policies " == *" $want "* ]] || { echo "FAIL: granted: expected $want (policy/priority)"; cat "$work/err_granted"; exit 1; }
done

# Thread names and a clean stop on SIGINT.
# Start-up (the camera's world, textures and rectification tables) takes a
# few seconds under emulation: wait for the threads rather than a fixed time.
"$rtfused" --duration 120 --quiet --lcm-url memq:// >"$work/out_sig" 2>"$work/err_sig" &
pid=$!
want=(rtfuse-loop rtfuse-pub rtfuse-lcmin rtfuse-imu rtfuse-camera rtfuse-sim)
for _ in $(seq 120); do
  sleep 0.5
  names=$(cat /proc/$pid/task/*/comm 2>/dev/null | sort | tr '\n' ' ')
  missing=0
  for n in "${want[@]}"; do [[ " $names " == *" $n "* ]] || missing=1; done
  ((missing == 0)) && break
done
echo "threads: $names"
for n in "${want[@]}"; do
  [[ " $names " == *" $n "* ]] || { echo "FAIL: no thread named $n within 60 s"; kill $pid; exit 1; }
done
sleep 1  # a second of running before the stop
kill -INT $pid
set +e
wait $pid
code=$?
set -e
[[ $code -eq 0 ]] || { echo "FAIL: SIGINT exit code $code"; exit 1; }
grep -q "position error against ground truth" "$work/out_sig" || { echo "FAIL: no final report after SIGINT"; exit 1; }
echo "1 passed, 0 failed"
