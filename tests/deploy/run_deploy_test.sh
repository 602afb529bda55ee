#!/usr/bin/env bash
# run_deploy_test.sh BUILD_DIR OUTDIR [NAME=VALUE]...
#
# tools/deploy.sh against a real "board": a Debian 12 root (debootstrap,
# cached) booted with systemd-nspawn, systemd as its PID 1 and sshd on
# 127.0.0.1:2222, in a private network namespace holding only lo. deploy.sh
# runs in the same namespace, so ssh and the LCM diagnostics it waits for
# travel over that loopback only (LCM URL with ttl=0).
#
#   good       the package from BUILD_DIR (cpack) + config/sim.toml: exit 0,
#              service active as user rtfuse with exactly its two capabilities,
#              status and a decoded diagnostics message in the output,
#              /etc/rtfuse/rtfused.toml identical to the file given
#   realtime   sim.toml + [realtime] require = true: the loop thread really
#              runs SCHED_FIFO with mlockall under the unit's capabilities
#   unreachable  nothing on the port: exit 3, fast
#   no-sudo    a user without sudo rights: exit 3
#   no-arch    a build dir with only an arm64 package: exit 4
#   bad-config rejected by the local check: exit 2, board untouched
#   daemon-rejects  the same config with --skip-check: exit 6, the daemon's
#              error from the journal in the output, service failed
#   no-hardware  config/robot_linux.toml (no can0 here): exit 6, the
#              daemon's error from the journal
#   redeploy   sim.toml again: exit 0, recovers the failed service
#   keep-config  no --config, the package found with --build-dir: exit 0,
#              the board's config unchanged
#
# NAME=VALUE: CPACK (cpack), REPLAY (rtfuse-replay for the local check),
# LCMTYPES (generated Python types), CACHE (board root cache, default
# BUILD_DIR/deploy-board), PREPARE_ONLY (1: make the cached root and stop;
# tools/test.sh does it beside the build).
#
# Exit: 0 pass, 1 fail, 77 skipped (not root, or a tool missing).
set -euo pipefail

SKIP=77
URL='udpm://239.255.76.67:7667?ttl=0'
PORT=2222
BOARD_USER=deployer
# What the board needs beyond minbase: an init, a bus, sshd, sudo for a
# non-root deploy user (a Jetson's default user is not root).
INCLUDE=systemd,systemd-sysv,dbus,openssh-server,sudo
MIRROR=http://deb.debian.org/debian

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
SRC=$(cd "$HERE/../.." && pwd)
DEPLOY=$SRC/tools/deploy.sh

if [[ $# -lt 2 ]]; then
  echo "usage: $0 BUILD_DIR OUTDIR [CPACK=..] [REPLAY=..] [LCMTYPES=..] [CACHE=..]" >&2
  exit 2
fi
build=$(cd "$1" && pwd) out=$2
shift 2
CPACK=cpack REPLAY='' LCMTYPES='' CACHE=$build/deploy-board PREPARE_ONLY=0
for kv in "$@"; do
  case "$kv" in
    CPACK=* | REPLAY=* | LCMTYPES=* | CACHE=* | PREPARE_ONLY=*) printf -v "${kv%%=*}" '%s' "${kv#*=}" ;;
    *) echo "$0: unknown setting '$kv'" >&2; exit 2 ;;
  esac
done

say() { echo "[deploy] $*"; }
fail() { echo "[deploy] FAIL: $*"; exit 1; }
skip() { echo "[deploy] SKIP: $*"; exit $SKIP; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

[[ $(id -u) -eq 0 ]] || skip "needs root (debootstrap, an overlay mount, ip netns, systemd-nspawn)"
for t in debootstrap systemd-nspawn ip ssh ssh-keygen lcm-logger dpkg-deb chroot mount "$CPACK" /usr/bin/python3; do
  command -v "$t" >/dev/null || skip "$t not found (tools/setup-deps.sh installs it)"
done
[[ $PREPARE_ONLY == 1 || -f $build/CPackConfig.cmake ]] ||
  fail "$build/CPackConfig.cmake missing: the build tree has no packaging (cmake/Packaging.cmake)"

mkdir -p "$out" "$CACHE"
out=$(cd "$out" && pwd)
rm -rf "$out/run"
mkdir -p "$out/run"
run=$out/run
NS=rtfuse-deploy-$$
MACHINE=rtfuse-board-$$
nspawn_pid=''
merged=$run/board/merged

cleanup() {
  set +e
  if [[ -n $nspawn_pid ]] && kill -0 "$nspawn_pid" 2>/dev/null; then
    kill -TERM "$nspawn_pid"  # nspawn turns it into a clean poweroff of the board
    for _ in $(seq 40); do kill -0 "$nspawn_pid" 2>/dev/null || break; sleep 0.5; done
    kill -0 "$nspawn_pid" 2>/dev/null && { say "board did not power off in 20 s, killing it"; kill -KILL "$nspawn_pid"; }
    wait "$nspawn_pid" 2>/dev/null
  fi
  mountpoint -q "$merged" && { umount "$merged" || umount -l "$merged"; }
  ip netns del "$NS" 2>/dev/null
  # nspawn will not delete under /run when /run is not a tmpfs (as here)
  rmdir "/run/systemd/nspawn/propagate/$MACHINE" 2>/dev/null
  rm -rf "$run/board/upper" "$run/board/work"
}
trap cleanup EXIT

# --- the board's root, made once and reused --------------------------------
root=$CACHE/root
stamp=$root/.rtfuse-board
exec 9>"$CACHE/lock"
flock 9  # one test at a time builds or changes the cache
if [[ ! -f $stamp || $(sed -n 1p "$stamp") != "$INCLUDE" ]]; then
  rm -rf "$root" "$CACHE/root.tmp"
  say "debootstrap bookworm ($INCLUDE) into $root, from $MIRROR"
  t0=$(now)
  debootstrap --variant=minbase --include="$INCLUDE" bookworm "$CACHE/root.tmp" "$MIRROR" \
    >"$CACHE/debootstrap.log" 2>&1 || { tail -20 "$CACHE/debootstrap.log"; fail "debootstrap failed"; }
  mv "$CACHE/root.tmp" "$root"
  printf '%s\ndebootstrap %s s\n' "$INCLUDE" "$(since "$t0")" >"$stamp"
fi
say "board root $root ($(sed -n 2p "$stamp"), reused when complete)"
# PREPARE_ONLY=1: only the cached root (tools/test.sh makes it beside the build).
if [[ $PREPARE_ONLY == 1 ]]; then
  say "prepared"
  exit 0
fi

# --- the package, packed from this build tree -------------------------------
t0=$(now)
(cd "$build" && "$CPACK" -G DEB --config CPackConfig.cmake -B "$run/pkg") >"$run/cpack.log" 2>&1 ||
  { cat "$run/cpack.log"; fail "cpack failed"; }
deb=$(find "$run/pkg" -maxdepth 1 -name 'rtfuse_*_amd64.deb' | head -n1)
[[ -n $deb ]] || { cat "$run/cpack.log"; fail "cpack made no rtfuse_*_amd64.deb"; }
depends=$(dpkg-deb -f "$deb" Depends)
say "package $(basename "$deb") ($(du -h "$deb" | cut -f1), cpack $(since "$t0") s), Depends: $depends"

# The board is offline (only lo): apt on it resolves the package's
# dependencies from its lists and finds them in its cache, as a board with a
# local mirror would. Filled here, on the host's network, like debootstrap.
if [[ ! -f $root/.rtfuse-deps || $(cat "$root/.rtfuse-deps") != "$depends" ]]; then
  say "downloading the package's dependencies into the board's apt cache"
  cp "$deb" "$root/tmp/rtfuse.deb"
  if ! { chroot "$root" apt-get update -q &&
         chroot "$root" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --download-only /tmp/rtfuse.deb
       } >"$run/apt-prep.log" 2>&1; then
    rm -f "$root/tmp/rtfuse.deb"
    tail -20 "$run/apt-prep.log"
    fail "apt-get --download-only in the board root failed"
  fi
  rm -f "$root/tmp/rtfuse.deb"
  printf '%s' "$depends" >"$root/.rtfuse-deps"
fi
flock -u 9

# --- this run's board: an overlay on the cached root -----------------------
mkdir -p "$run/board/upper" "$run/board/work" "$merged"
mount -t overlay overlay -o "lowerdir=$root,upperdir=$run/board/upper,workdir=$run/board/work" "$merged"
ssh-keygen -q -t ed25519 -N '' -C rtfuse-deploy-test -f "$run/id_ed25519"
echo board >"$merged/etc/hostname"
printf '127.0.0.1 localhost\n127.0.1.1 board\n::1 localhost\n' >"$merged/etc/hosts"  # sudo looks up its host name
cat >"$merged/etc/ssh/sshd_config.d/rtfuse-test.conf" <<EOF
Port $PORT
ListenAddress 127.0.0.1
PasswordAuthentication no
KbdInteractiveAuthentication no
EOF
chroot "$merged" useradd -m -s /bin/bash -G sudo "$BOARD_USER"
echo "$BOARD_USER ALL=(root) NOPASSWD: ALL" >"$merged/etc/sudoers.d/$BOARD_USER"
# and one the same key logs in as, without sudo rights
chroot "$merged" useradd -m -s /bin/bash nosudo
for u in "$BOARD_USER" nosudo; do
  install -d -m 700 "$merged/home/$u/.ssh"
  install -m 600 "$run/id_ed25519.pub" "$merged/home/$u/.ssh/authorized_keys"
  chroot "$merged" chown -R "$u:$u" "/home/$u/.ssh"
done
# The board's own host key, so ssh checks it strictly.
echo "[127.0.0.1]:$PORT $(cut -d' ' -f1,2 "$merged/etc/ssh/ssh_host_ed25519_key.pub")" >"$run/known_hosts"

# --- the private network: lo only, multicast routed to it -----------------
ip netns add "$NS"
ip -n "$NS" link set lo up
ip -n "$NS" route add 224.0.0.0/4 dev lo
links=$(ip -n "$NS" -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
[[ $links == "lo " ]] || fail "network namespace $NS is not private (links: $links)"

# --- boot ----------------------------------------------------------------
# --register=no --keep-unit: no machined or systemd scope needed on the host.
# CAP_IPC_LOCK is not in nspawn's default set; a real board has it, and the
# unit's CapabilityBoundingSet asks for it.
say "booting the board: systemd-nspawn -b in $NS"
t0=$(now)
systemd-nspawn -b -D "$merged" -M "$MACHINE" --network-namespace-path="/run/netns/$NS" \
  --register=no --keep-unit --capability=CAP_IPC_LOCK --console=read-only </dev/null >"$out/board-console.log" 2>&1 &
nspawn_pid=$!

ssh_opts=(-p "$PORT" -i "$run/id_ed25519" -o IdentitiesOnly=yes -o BatchMode=yes -o ConnectTimeout=5
          -o StrictHostKeyChecking=yes -o "UserKnownHostsFile=$run/known_hosts")
board() { ip netns exec "$NS" ssh "${ssh_opts[@]}" "$BOARD_USER@127.0.0.1" "$@"; }
up=0
for _ in $(seq 120); do
  kill -0 "$nspawn_pid" 2>/dev/null || { cat "$out/board-console.log"; fail "systemd-nspawn exited while booting"; }
  if board true 2>/dev/null; then up=1; break; fi
  sleep 0.5
done
((up)) || { cat "$out/board-console.log"; fail "the board's sshd did not answer within 60 s of the boot"; }
boot_ssh=$(since "$t0")
state=$(board 'timeout 60 systemctl is-system-running --wait' 2>&1 || true)
boot_done=$(since "$t0")
[[ $(board 'cat /proc/1/comm') == systemd ]] || fail "PID 1 on the board is not systemd"
say "board up: ssh after $boot_ssh s, systemd '$state' after $boot_done s"
[[ $state == running ]] || { board 'systemctl --failed --no-pager' || true; fail "the board booted '$state', not 'running'"; }

# --- deploy.sh --------------------------------------------------------------
deploy() { # deploy NAME ARGS...: runs deploy.sh in the namespace; sets rc, took, log
  local name=$1 t
  shift
  log=$out/deploy-$name.log
  t=$(now)
  rc=0
  ip netns exec "$NS" env RTFUSE_REPLAY="$REPLAY" ${LCMTYPES:+RTFUSE_LCMTYPES_PYTHON="$LCMTYPES"} \
    "$DEPLOY" 127.0.0.1 --port "$PORT" --user "$BOARD_USER" --identity "$run/id_ed25519" \
    --ssh-option StrictHostKeyChecking=yes --ssh-option "UserKnownHostsFile=$run/known_hosts" \
    --lcm-url "$URL" "$@" >"$log" 2>&1 || rc=$?
  took=$(since "$t")
  sed 's/^/    /' "$log"
  say "$name: deploy.sh exit $rc in $took s"
}
expect() { # expect PATTERN WHAT: an extended regex in the last deploy's output
  grep -qE -- "$1" "$log" || fail "$2 (no /$1/ in $log)"
}
main_pid() { board 'systemctl show -p MainPID --value rtfused.service'; }
config_is() { # config_is FILE: the board's /etc/rtfuse/rtfused.toml is byte for byte FILE
  board 'cat /etc/rtfuse/rtfused.toml' | cmp -s - "$1"
}

sim=$SRC/config/sim.toml
say "--- good: $(basename "$deb") + config/sim.toml"
deploy good --package "$deb" --config "$sim" --timeout 20
[[ $rc -eq 0 ]] || fail "deploy.sh exited $rc on a good deploy"
good_time=$took
expect 'Active: active \(running\)' "no systemctl status of the running service"
expect '^--- first rtfuse/diagnostics message' "no diagnostics message"
expect 'loop [0-9.]+ Hz .*, [1-9][0-9]* ticks' "the diagnostics message shows no running loop"
expect '^  sensor wheels: ' "the decoded diagnostics lack the wheels sensor"
expect '^  device ' "the decoded diagnostics lack the devices"
[[ $(board 'systemctl is-active rtfused.service') == active ]] || fail "rtfused.service is not active after the deploy"
config_is "$sim" || fail "/etc/rtfuse/rtfused.toml on the board differs from $sim"
pid=$(main_pid)
owner=$(board "stat -c %U /proc/$pid")
caps=$(board "grep -E '^Cap(Eff|Bnd|Amb)' /proc/$pid/status" | tr -s '\t\n' '  ')
say "rtfused pid $pid runs as '$owner', $caps"
[[ $owner == rtfuse ]] || fail "rtfused runs as '$owner', not the unprivileged rtfuse user"
# CAP_IPC_LOCK (14) and CAP_SYS_NICE (23), nothing else
[[ $caps == *"CapEff: 0000000000804000"* ]] || fail "rtfused's effective capabilities are not exactly CAP_SYS_NICE + CAP_IPC_LOCK: $caps"

say "--- realtime: sim.toml with [realtime] priority 50, lock_memory, require = true"
rt=$run/rt.toml
{ cat "$sim"; printf '\n[realtime]\nlock_memory = true\npriority = 50\nrequire = true\n'; } >"$rt"
deploy realtime --package "$deb" --config "$rt" --timeout 20
[[ $rc -eq 0 ]] || fail "the board refused the real-time settings under the unit's capabilities (exit $rc)"
pid=$(main_pid)
# /proc/PID/task/*/stat: field 40 rt_priority, 41 policy (1 = SCHED_FIFO);
# after cutting 'pid (comm) ' they are $38 and $39
fifo=$(board "cat /proc/$pid/task/*/stat" | sed 's/.*) //' | awk '$38 == 50 && $39 == 1' | wc -l)
locked=$(board "sed -n 's/^VmLck:[[:space:]]*//p' /proc/$pid/status")
say "rtfused: $fifo thread(s) SCHED_FIFO 50, VmLck $locked"
((fifo >= 1)) || fail "no rtfused thread runs SCHED_FIFO at priority 50"
[[ ${locked%% *} -gt 0 ]] || fail "rtfused has no locked memory (mlockall did not take)"

say "--- unreachable: nothing listens on port 2299"
t0=$(now)
rc=0
ip netns exec "$NS" "$DEPLOY" 127.0.0.1 --port 2299 --identity "$run/id_ed25519" --package "$deb" \
  --ssh-option "UserKnownHostsFile=$run/known_hosts" >"$out/deploy-unreachable.log" 2>&1 || rc=$?
log=$out/deploy-unreachable.log took=$(since "$t0")
sed 's/^/    /' "$log"
say "unreachable: deploy.sh exit $rc in $took s"
[[ $rc -eq 3 ]] || fail "unreachable board: exit $rc, expected 3"
expect 'Connection refused' "ssh's reason is not shown"
expect 'cannot log in to 127\.0\.0\.1' "no clear error for an unreachable board"
awk -v t="$took" 'BEGIN { exit !(t < 5) }' || fail "unreachable board: took $took s, expected < 5 s"

say "--- no-sudo: a user who may not use sudo"
deploy no-sudo --package "$deb" --config "$sim" --user nosudo
[[ $rc -eq 3 ]] || fail "a user without sudo: exit $rc, expected 3"
expect 'cannot use sudo without a password' "no clear error for a user without sudo"

say "--- no-arch: a build tree with only an arm64 package"
mkdir -p "$run/arm64-build/packages"
cp "$deb" "$run/arm64-build/packages/rtfuse_0.0.0_arm64.deb"
deploy no-arch --build-dir "$run/arm64-build" --config "$sim"
[[ $rc -eq 4 ]] || fail "no package for the board's architecture: exit $rc, expected 4"
expect 'no rtfuse_\*_amd64\.deb under' "no clear error for a missing package"

say "--- bad-config: an unknown key, rejected before anything is copied"
bad=$run/bad.toml
sed 's/^two_d_mode = true/two_d_mod = true/' "$sim" >"$bad"
! cmp -s "$bad" "$sim" || fail "could not make the bad config"
deploy bad-config --package "$deb" --config "$bad"
if [[ -x $REPLAY ]]; then
  [[ $rc -eq 2 ]] || fail "a config the loader rejects: exit $rc, expected 2"
  expect "bad\.toml:[0-9]+:[0-9]+.*two_d_mod" "the loader's error (file:line:column, key) is not shown"
  config_is "$rt" || fail "a rejected config changed the board's /etc/rtfuse/rtfused.toml"
  [[ $(board 'systemctl is-active rtfused.service') == active ]] || fail "a rejected config stopped the service"
else
  say "no rtfuse-replay (REPLAY=$REPLAY): the local check cannot run, skipping this case"
fi

say "--- daemon-rejects: the same config with --skip-check: the daemon exits 2"
deploy daemon-rejects --package "$deb" --config "$bad" --skip-check --timeout 5
[[ $rc -eq 6 ]] || fail "a config the daemon rejects: exit $rc, expected 6"
expect '/etc/rtfuse/rtfused\.toml:[0-9]+:[0-9]+.*two_d_mod' "the daemon's error from the journal is not shown"
expect 'failed to start' "no clear error for a failed service"
[[ $(board 'systemctl is-active rtfused.service' || true) == failed ]] || fail "the service is not 'failed' after exit 2"
config_is "$bad" || fail "/etc/rtfuse/rtfused.toml is not the deployed config"

say "--- no-hardware: config/robot_linux.toml, no can0 on this board"
deploy no-hardware --package "$deb" --config "$SRC/config/robot_linux.toml" --timeout 5
[[ $rc -eq 6 ]] || fail "a daemon that cannot open its buses: exit $rc, expected 6"
expect 'rtfused\[[0-9]+\]: .*can0' "the daemon's error about can0 is not shown from the journal"

say "--- redeploy: sim.toml again, out of the failed state"
deploy redeploy --package "$deb" --config "$sim" --timeout 20
[[ $rc -eq 0 ]] || fail "redeploying the good config: exit $rc"
redeploy_time=$took
expect '^--- first rtfuse/diagnostics message' "no diagnostics message after the redeploy"
config_is "$sim" || fail "/etc/rtfuse/rtfused.toml differs from $sim after the redeploy"

say "--- keep-config: no --config, the package found with --build-dir"
deploy keep-config --build-dir "$run" --timeout 20
[[ $rc -eq 0 ]] || fail "deploying without --config: exit $rc"
expect "package $run/pkg/rtfuse_[^ ]*_amd64\.deb" "--build-dir did not find the package"
expect '^--- first rtfuse/diagnostics message from the running loop' "no diagnostics from the running loop"
config_is "$sim" || fail "a deploy without --config changed /etc/rtfuse/rtfused.toml"

say "times: debootstrap $(sed -n 2p "$stamp" | cut -d' ' -f2-) (once, then cached), boot $boot_ssh s to ssh / $boot_done s to 'running', deploy $good_time s (first), $redeploy_time s (redeploy)"
say "PASS"
