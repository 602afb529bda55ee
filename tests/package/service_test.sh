#!/usr/bin/env bash
# service_test.sh ROOT
#
# rtfused.service as systemd runs it: boots ROOT (rtfuse and systemd
# installed, nothing mounted in it) with systemd-nspawn, systemd as PID 1 and
# a private network (lo only), and checks inside:
#   - the service starts as user rtfuse with exactly CAP_IPC_LOCK and
#     CAP_SYS_NICE (effective, ambient, bounding), its loop thread in
#     SCHED_FIFO 80 and its memory locked: a config with [realtime]
#     require = true, so a refused setting would exit 3;
#   - killed, it is restarted (Restart=on-failure);
#   - with a bad config it exits 2 and stays failed (RestartPreventExitStatus).
# ROOT's /etc/rtfuse/rtfused.toml is replaced during the run and put back.
# Native architecture only: under qemu-user, seccomp filters and
# MemoryDenyWriteExecute (qemu's code generator writes code) are not the
# board's, so a failure there would say nothing about the unit.
# Exit: 0 passed, 1 a check failed, 2 usage, 77 systemd-nspawn missing.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
source "$here/lib.sh"

if (($# != 1)) || [[ ! -d $1 ]]; then echo "usage: $0 ROOT" >&2; exit 2; fi
root=$(readlink -f "$1")
command -v systemd-nspawn >/dev/null || skip "systemd-nspawn not installed (apt-get install systemd-container)"
[[ -x $root/lib/systemd/systemd && -f $root/lib/systemd/system/rtfused.service ]] ||
  { echo "$0: $root lacks systemd or rtfuse" >&2; exit 2; }

machine=rtfuse-pkg-$$
conf=$root/etc/rtfuse/rtfused.toml
cp -p "$conf" "$root/etc/rtfuse/.rtfused.toml.orig"
cleanup() {
  mv -f "$root/etc/rtfuse/.rtfused.toml.orig" "$conf"
  rm -f "$root/etc/systemd/system/rtfuse-service-check.service" \
        "$root/etc/systemd/system/multi-user.target.wants/rtfuse-service-check.service" \
        "$root/root/rtfuse-service-check.sh"
  # nspawn leaves this behind when /run is not a tmpfs.
  rmdir "/run/systemd/nspawn/propagate/$machine" 2>/dev/null || true
}
trap cleanup EXIT

# The simulated robot, in-process LCM, real time required.
{
  sed 's|^url = .*|url = "memq://"|' "$root/etc/rtfuse/sim.toml"
  printf '\n[realtime]\nlock_memory = true\npriority = 80\nrequire = true\n'
} >"$conf"

cat >"$root/root/rtfuse-service-check.sh" <<'EOF'
#!/bin/sh
# Inside the booted root: key=value lines to /root/rtfuse-service-result.
out=/root/rtfuse-service-result
: >"$out"
say() { echo "$*" >>"$out"; }
prop() { systemctl show -p "$1" --value rtfused.service; }
loop_tid() {
    for t in /proc/"$(prop MainPID)"/task/*; do
        [ "$(cat "$t/comm" 2>/dev/null)" = rtfuse-loop ] && { basename "$t"; return; }
    done
}
# wait_for SECONDS CONDITION...
wait_for() {
    n=$(($1 * 2)); shift
    while [ "$n" -gt 0 ]; do "$@" && return 0; sleep 0.5; n=$((n - 1)); done
    return 1
}
running() { [ "$(prop ActiveState)" = active ] && [ -n "$(loop_tid)" ]; }
restarted() { [ "$(prop NRestarts)" -ge 1 ] && running; }

systemctl start rtfused.service
if wait_for 20 running; then
    p=$(prop MainPID)
    say "active=yes"
    say "user=$(stat -c %U /proc/"$p")"
    grep -E '^Cap(Eff|Amb|Bnd):' /proc/"$p"/status | tr -d ' \t' | tr ':' '=' >>"$out"
    say "loop_policy=$(chrt -p "$(loop_tid)" | sed -n 's/.*policy: //p')"
    say "loop_priority=$(chrt -p "$(loop_tid)" | sed -n 's/.*priority: //p')"
    say "vmlck_kb=$(awk '/^VmLck:/ {print $2}' /proc/"$p"/status)"
    systemctl kill --kill-who=main --signal=SIGKILL rtfused.service
    if wait_for 30 restarted; then say "restarted=yes"; else say "restarted=no state=$(prop ActiveState)/$(prop SubState)"; fi
    echo 'not = = toml' >/etc/rtfuse/rtfused.toml
    systemctl restart rtfused.service
    before=$(prop NRestarts)
    sleep 12  # > 2 x RestartSec: a restart loop would have started again
    say "bad_config=$(prop ActiveState)/$(prop SubState)/$(prop Result)/$(prop ExecMainStatus)/restarts+$(($(prop NRestarts) - before))"
else
    say "active=no state=$(prop ActiveState)/$(prop SubState)/$(prop Result)/$(prop ExecMainStatus)"
fi
journalctl -u rtfused.service --no-pager -o cat >/root/rtfuse-service-journal 2>&1
systemctl poweroff
EOF
chmod 755 "$root/root/rtfuse-service-check.sh"
cat >"$root/etc/systemd/system/rtfuse-service-check.service" <<'EOF'
[Unit]
Description=rtfuse package test: rtfused.service under systemd
After=multi-user.target
[Service]
Type=oneshot
ExecStart=/root/rtfuse-service-check.sh
[Install]
WantedBy=multi-user.target
EOF
mkdir -p "$root/etc/systemd/system/multi-user.target.wants"
ln -sf /etc/systemd/system/rtfuse-service-check.service \
  "$root/etc/systemd/system/multi-user.target.wants/rtfuse-service-check.service"
rm -f "$root/root/rtfuse-service-result" "$root/root/rtfuse-service-journal"

# CAP_IPC_LOCK is not in nspawn's default set; a board's systemd has it.
# --register=no --keep-unit: no machined or host systemd needed.
t0=$(date +%s)
log=$(mktemp)
rc=0
timeout 180 systemd-nspawn -q -b -D "$root" -M "$machine" --private-network --register=no --keep-unit \
  --capability=CAP_IPC_LOCK --console=read-only </dev/null >"$log" 2>&1 || rc=$?
result=$root/root/rtfuse-service-result
if [[ ! -s $result ]]; then
  tail -n 30 "$log" >&2
  rm -f "$log"
  die "the booted root wrote no result (systemd-nspawn exit $rc)"
fi
cp "$log" "$root/root/rtfuse-service-console.log"; rm -f "$log"
note "service run under systemd-nspawn in $(($(date +%s) - t0)) s: $(tr '\n' ' ' <"$result")"

val() { sed -n "s/^$1=//p" "$result" | head -n1; }
fail=0
check() {  # check WHAT GOT WANT
  if [[ $2 != "$3" ]]; then echo "FAIL: rtfused.service: $1 is '$2', expected '$3'" >&2; fail=1; fi
}
check "started" "$(val active)" yes
# CAP_IPC_LOCK (14) and CAP_SYS_NICE (23), nothing else.
caps=0000000000804000
check "user" "$(val user)" rtfuse
check "CapEff" "$(val CapEff)" $caps
check "CapAmb" "$(val CapAmb)" $caps
check "CapBnd" "$(val CapBnd)" $caps
check "the loop thread's policy" "$(val loop_policy)" SCHED_FIFO
check "the loop thread's priority" "$(val loop_priority)" 80
vmlck=$(val vmlck_kb)
[[ ${vmlck:-0} -gt 1024 ]] || { echo "FAIL: rtfused.service: VmLck ${vmlck:-?} kB, memory not locked" >&2; fail=1; }
check "restart after SIGKILL" "$(val restarted)" yes
check "bad config: state/substate/result/exit status/restarts" "$(val bad_config)" "failed/failed/exit-code/2/restarts+0"
if ((fail)); then
  echo "--- journal of rtfused.service:" >&2
  tail -n 40 "$root/root/rtfuse-service-journal" >&2 || true
  exit 1
fi
rm -f "$result" "$root/root/rtfuse-service-journal" "$root/root/rtfuse-service-console.log"
echo "service_test: rtfused.service runs as rtfuse with CAP_IPC_LOCK+CAP_SYS_NICE, SCHED_FIFO 80, ${vmlck} kB locked; restarts after a kill, not after exit 2"
