#!/usr/bin/env bash
# deploy.sh HOST [options]: puts rtfuse on a board over ssh and checks it runs.
#
#   1. asks the board its architecture (dpkg --print-architecture) and picks
#      the rtfuse_*_<arch>.deb (--package, or the newest one in --build-dir)
#   2. checks the config locally with rtfuse-replay when one runs here
#   3. copies the package (and config) over ssh, installs it with
#      `apt-get install ./rtfuse_*.deb` (dependencies resolve from the board's
#      apt sources; sudo -n when the ssh user is not root), installs the
#      config as /etc/rtfuse/rtfused.toml (the old one kept as .prev)
#   4. restarts rtfused.service, waits until it stays up, prints
#      `systemctl status rtfused`, or the journal when the daemon fails
#   5. waits for the first rtfuse/diagnostics message over LCM here on the
#      workstation (lcm-logger) and prints it decoded
#
# Exit status:
#   0 deployed, service running, diagnostics received
#   2 usage error, a local file missing, or the config rejected by the check
#   3 the board cannot be reached or logged into over ssh, or no root on it
#   4 no package for the board's architecture
#   5 copying or installing the package or the config failed
#   6 the service did not start or does not stay up (its journal is printed)
#   7 no diagnostics message within --timeout (or lcm-logger cannot listen)
set -euo pipefail

readonly LCM_DEFAULT_URL_BUILTIN='udpm://239.255.76.67:7667?ttl=0'  # LCM's own default
readonly REMOTE_CONFIG=/etc/rtfuse/rtfused.toml
readonly UNIT=rtfused.service
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PYTHON=${RTFUSE_PYTHON:-/usr/bin/python3}

E_USAGE=2 E_SSH=3 E_PACKAGE=4 E_INSTALL=5 E_SERVICE=6 E_DIAG=7

usage() {
  cat >&2 <<EOF
usage: $0 HOST [options]
  HOST                the board, [USER@]NAME or address
  --config FILE       rtfused config to install as $REMOTE_CONFIG
                      (default: keep the board's)
  --package FILE      the rtfuse .deb (must match the board's architecture)
  --build-dir DIR     take the newest rtfuse_*_<arch>.deb under DIR
                      (default: $REPO/build)
  --port N            ssh port (default: ssh's, 22)
  --user NAME         ssh user (default: from HOST or ssh's config)
  --identity FILE     ssh private key
  --ssh-option OPT    extra 'ssh -o OPT' (repeatable), e.g. UserKnownHostsFile=F
  --lcm-url URL       where to listen for diagnostics (default: \$LCM_DEFAULT_URL
                      or $LCM_DEFAULT_URL_BUILTIN; on the robot's network
                      use ttl=1, here and in the config's [lcm] url)
  --timeout S         seconds to wait for the first diagnostics message (default 15)
  --settle S          seconds the service must stay up after the restart (default 3)
  --skip-check        do not check the config locally before installing it
  -h, --help
exit: 0 ok, 2 usage/bad config, 3 ssh, 4 no package for the arch,
      5 install failed, 6 service failed (journal printed), 7 no diagnostics
EOF
  exit $E_USAGE
}

say() { echo "deploy: $*"; }
elapsed() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }
die() { # die CODE MESSAGE...
  local code=$1
  shift
  echo "deploy: error: $*" >&2
  exit "$code"
}

host='' config='' package='' build_dir='' port='' user='' identity='' skip_check=0
lcm_url=${LCM_DEFAULT_URL:-$LCM_DEFAULT_URL_BUILTIN} timeout_s=15 settle_s=3
ssh_options=()
need() { [[ $# -ge 2 && -n $2 ]] || { echo "$0: $1 needs a value" >&2; usage; }; }
while (($#)); do
  case "$1" in
    --config) need "$@"; config=$2; shift 2 ;;
    --package) need "$@"; package=$2; shift 2 ;;
    --build-dir) need "$@"; build_dir=$2; shift 2 ;;
    --port) need "$@"; port=$2; shift 2 ;;
    --user) need "$@"; user=$2; shift 2 ;;
    --identity) need "$@"; identity=$2; shift 2 ;;
    --ssh-option) need "$@"; ssh_options+=(-o "$2"); shift 2 ;;
    --lcm-url) need "$@"; lcm_url=$2; shift 2 ;;
    --timeout) need "$@"; timeout_s=$2; shift 2 ;;
    --settle) need "$@"; settle_s=$2; shift 2 ;;
    --skip-check) skip_check=1; shift ;;
    -h | --help) usage ;;
    -*) echo "$0: unknown option '$1'" >&2; usage ;;
    *) [[ -z $host ]] || { echo "$0: more than one HOST ('$host', '$1')" >&2; usage; }
       host=$1; shift ;;
  esac
done
[[ -n $host ]] || { echo "$0: no HOST given" >&2; usage; }
[[ -z $port || $port =~ ^[0-9]+$ ]] || die $E_USAGE "--port: '$port' is not a port number"
[[ $timeout_s =~ ^[0-9]+$ && $timeout_s -gt 0 ]] || die $E_USAGE "--timeout: '$timeout_s' is not a whole number of seconds > 0"
[[ $settle_s =~ ^[0-9]+$ ]] || die $E_USAGE "--settle: '$settle_s' is not a whole number of seconds"
[[ $lcm_url == udpm://* ]] || die $E_USAGE "--lcm-url: '$lcm_url' is not a udpm:// URL"
for f in "$config" "$package" "$identity"; do
  [[ -z $f || -r $f ]] || die $E_USAGE "$f: no such file or not readable"
done
[[ -z $build_dir || -d $build_dir ]] || die $E_USAGE "--build-dir $build_dir: not a directory"
[[ -z $package || -z $build_dir ]] || die $E_USAGE "give --package or --build-dir, not both"
for tool in ssh lcm-logger "$PYTHON"; do
  command -v "$tool" >/dev/null || die $E_USAGE "$tool not found (apt-get install openssh-client liblcm-bin python3)"
done

start_time=$(date +%s.%N)
tmp=$(mktemp -d /tmp/rtfuse-deploy.XXXXXX)
logger_pid='' rdir=''
# ssh takes the first value of an option: --ssh-option overrides these defaults
ssh_cmd=(ssh "${ssh_options[@]}" -o BatchMode=yes -o ConnectTimeout=10 -o ServerAliveInterval=5 -o ServerAliveCountMax=3
         -o StrictHostKeyChecking=accept-new
         # one connection for all the steps below
         -o ControlMaster=auto -o "ControlPath=$tmp/ssh-%C" -o ControlPersist=300)
[[ -z $port ]] || ssh_cmd+=(-p "$port")
[[ -z $user ]] || ssh_cmd+=(-l "$user")
[[ -z $identity ]] || ssh_cmd+=(-i "$identity" -o IdentitiesOnly=yes)

cleanup() {
  set +e
  [[ -z $logger_pid ]] || { kill "$logger_pid" 2>/dev/null; wait "$logger_pid" 2>/dev/null; }
  [[ -z $rdir ]] || "${ssh_cmd[@]}" "$host" "rm -rf '$rdir'" >/dev/null 2>&1
  "${ssh_cmd[@]}" -O exit "$host" >/dev/null 2>&1
  rm -rf "$tmp"
}
trap cleanup EXIT

remote() { "${ssh_cmd[@]}" "$host" "$@"; }

# --- the config: the diagnostics channel and the daemon's LCM URL ----------
# tomllib only reads the two keys this script needs; judging the config is
# rtfuse-replay's job below (the same loader as rtfused).
config_info() { # config_info FILE: prints "channel rate url"
  "$PYTHON" - "$1" <<'EOF'
import sys, tomllib
try:
    with open(sys.argv[1], "rb") as f:
        t = tomllib.load(f)
except (OSError, tomllib.TOMLDecodeError) as e:
    print(f"{sys.argv[1]}: {e}", file=sys.stderr)
    sys.exit(1)
pub = t.get("publish", {}) if isinstance(t.get("publish"), dict) else {}
lcm = t.get("lcm", {}) if isinstance(t.get("lcm"), dict) else {}
print(pub.get("diagnostics_channel", "rtfuse/diagnostics"), pub.get("diagnostics_rate", 1),
      lcm.get("url", "udpm://239.255.76.67:7667?ttl=0"))
EOF
}

if [[ -n $config && $skip_check -eq 0 ]]; then
  # rtfused has no check-only mode; rtfuse-replay loads a config with the same
  # loader and, given an empty log, does nothing else (no bus, no network).
  checker=''
  for c in "${RTFUSE_REPLAY:-}" "${build_dir:+$build_dir/src/apps/rtfuse-replay}" \
           "$REPO/build/release/src/apps/rtfuse-replay" "$REPO/build/test/src/apps/rtfuse-replay" \
           "$(command -v rtfuse-replay || true)"; do
    if [[ -n $c && -x $c ]] && "$c" --help >/dev/null 2>&1; then checker=$c; break; fi
  done
  if [[ -z $checker ]]; then
    say "no runnable rtfuse-replay here to check $config (set RTFUSE_REPLAY); the daemon checks it on the board"
  else
    : >"$tmp/empty.lcm"
    if ! out=$("$checker" --config "$config" --log "$tmp/empty.lcm" --quiet 2>&1 >/dev/null); then
      printf '%s\n' "$out" >&2
      die $E_USAGE "$config is rejected by $checker (nothing was changed on $host; --skip-check to install it anyway)"
    fi
    say "config $config: accepted by $checker"
  fi
fi
if [[ -n $config ]] && ! info=$(config_info "$config" 2>&1); then
  ((skip_check)) || die $E_USAGE "$config: not valid TOML: $info"
  say "warning: $config is not valid TOML ($info); installing it anyway (--skip-check)"
  info="rtfuse/diagnostics 1 $LCM_DEFAULT_URL_BUILTIN"
fi

# --- 1. the board ---------------------------------------------------------
say "connecting to $host${port:+ port $port}"
# shellcheck disable=SC2016  # expanded on the board
if ! probe=$(remote 'printf "%s %s\n" "$(dpkg --print-architecture 2>/dev/null || echo none)" "$(id -u)"' 2>"$tmp/ssh.err"); then
  sed 's/^/  ssh: /' "$tmp/ssh.err" >&2
  die $E_SSH "cannot log in to $host over ssh (is it up, is sshd listening${port:+ on port $port}, is the key authorized?)"
fi
read -r arch uid <<<"$probe"
[[ $arch != none ]] || die $E_PACKAGE "$host has no dpkg: not a Debian/Ubuntu system, cannot install a .deb"
sudo=
if [[ $uid != 0 ]]; then
  sudo='sudo -n'
  remote 'sudo -n true' 2>"$tmp/ssh.err" ||
    die $E_SSH "the ssh user on $host is not root and cannot use sudo without a password: $(tr '\n' ' ' <"$tmp/ssh.err")
  (deploy as root, or allow it: '<user> ALL=(root) NOPASSWD: ALL' in /etc/sudoers.d/)"
fi
say "$host: architecture $arch, $([[ -z $sudo ]] && echo root || echo "uid $uid, using sudo")"

# --- 2. the package ---------------------------------------------------------
if [[ -n $package ]]; then
  pkg_arch=$(dpkg-deb -f "$package" Architecture 2>/dev/null) ||
    die $E_PACKAGE "$package: not a Debian package (dpkg-deb cannot read it)"
  [[ $pkg_arch == "$arch" || $pkg_arch == all ]] ||
    die $E_PACKAGE "$package is for $pkg_arch, $host is $arch"
else
  dir=${build_dir:-$REPO/build}
  # CPack leaves a staging copy under _CPack_Packages; the one to ship is above it.
  package=$(find "$dir" -maxdepth 3 -path '*/_CPack_Packages' -prune -o -type f -name "rtfuse_*_${arch}.deb" \
              -printf '%T@ %p\n' 2>/dev/null | sort -rn | head -n1 | cut -d' ' -f2-)
  [[ -n $package ]] || die $E_PACKAGE "no rtfuse_*_${arch}.deb under $dir for $host ($arch)
  (build it there: cmake --build DIR && (cd DIR && cpack -G DEB), or give --package FILE)"
fi
pkg_name=$(basename "$package")
say "package $package ($(du -h "$package" | cut -f1))"

# --- 3. copy and install ----------------------------------------------------
# shellcheck disable=SC2016  # expanded on the board
rdir=$(remote 'd=$(mktemp -d /tmp/rtfuse-deploy.XXXXXX) && chmod 755 "$d" && echo "$d"') ||
  die $E_INSTALL "cannot make a temporary directory on $host"
copy() { # copy LOCAL REMOTE_NAME: over the ssh connection, checked by checksum
  local sum
  remote "cat > '$rdir/$2' && chmod 644 '$rdir/$2'" <"$1" || die $E_INSTALL "copying $1 to $host failed"
  sum=$(remote "sha256sum '$rdir/$2'" | cut -d' ' -f1)
  [[ $sum == "$(sha256sum "$1" | cut -d' ' -f1)" ]] || die $E_INSTALL "$1 arrived damaged on $host (checksum differs)"
}
t=$(date +%s.%N)
copy "$package" "$pkg_name"
[[ -z $config ]] || copy "$config" rtfused.toml
say "copied to $host:$rdir in $(elapsed "$t") s"

# --reinstall: a rebuilt package often keeps its version number; confold keeps
# the board's configs (the one given here is installed next).
say "installing $pkg_name"
t=$(date +%s.%N)
if ! remote "cd '$rdir' && $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --reinstall \
      --allow-downgrades -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold './$pkg_name'" \
      >"$tmp/apt.out" 2>&1; then
  sed 's/^/  /' "$tmp/apt.out" >&2
  die $E_INSTALL "installing $pkg_name on $host failed (apt-get output above)"
fi
grep -E '^(Setting up|Unpacking|[0-9]+ upgraded)' "$tmp/apt.out" | sed 's/^/  /' || true
say "installed in $(elapsed "$t") s"

if [[ -n $config ]]; then
  remote "set -e; $sudo install -d -m 755 /etc/rtfuse
    if [ -f $REMOTE_CONFIG ]; then $sudo cp -p $REMOTE_CONFIG $REMOTE_CONFIG.prev; fi
    $sudo install -m 644 -o root -g root '$rdir/rtfused.toml' $REMOTE_CONFIG" 2>"$tmp/ssh.err" ||
    die $E_INSTALL "installing the config as $REMOTE_CONFIG failed: $(cat "$tmp/ssh.err")"
  say "installed $config as $REMOTE_CONFIG (previous one: $REMOTE_CONFIG.prev)"
else
  remote "cat $REMOTE_CONFIG" >"$tmp/board.toml" 2>/dev/null ||
    die $E_INSTALL "no --config given and $host has no $REMOTE_CONFIG"
  info=$(config_info "$tmp/board.toml" 2>&1) || info="rtfuse/diagnostics 1 $LCM_DEFAULT_URL_BUILTIN"
fi
read -r diag_channel diag_rate daemon_url <<<"$info"

# The daemon's messages reach this machine only with the same group and port
# and a TTL that lets them off the board.
group_port() { local u=${1#udpm://}; echo "${u%%\?*}"; }
[[ $(group_port "$daemon_url") == "$(group_port "$lcm_url")" ]] ||
  say "warning: the daemon publishes on $daemon_url, listening on $lcm_url: different group or port"
if [[ $daemon_url == *ttl=0* || $daemon_url != *ttl=* ]] &&
   [[ ! $host =~ (^|@)(localhost|127\.[0-9.]+|::1)$ ]]; then
  say "warning: the daemon's [lcm] url $daemon_url has ttl=0: its messages stay on $host; use ttl=1 on the robot's network"
fi

# --- 4. restart -------------------------------------------------------------
restarts_before=$(remote "systemctl show -p NRestarts --value $UNIT" 2>/dev/null || echo 0)
since=$(remote 'date +%s')
say "restarting $UNIT"
restart_time=$(date +%s.%N)
remote "$sudo systemctl enable --quiet $UNIT 2>/dev/null; $sudo systemctl restart $UNIT" >"$tmp/restart.out" 2>&1 ||
  restart_failed=1

# Listen from now on: the old instance is gone, every message is the new one's.
diag_log=$tmp/diagnostics.lcm
if ((diag_rate > 0)); then
  lcm-logger -q -f --flush-interval=50 -c "$diag_channel" --lcm-url="$lcm_url" "$diag_log" \
    >"$tmp/logger.out" 2>&1 &
  logger_pid=$!
fi

journal_tail() {
  echo "--- journalctl -u $UNIT (since the restart) ---"
  remote "$sudo journalctl -u $UNIT --since @$since --no-pager -n 40 -o short-precise" 2>&1 | sed 's/^/  /'
}
service_failed() {
  remote "$sudo systemctl status $UNIT --no-pager -l -n 0" 2>&1 | sed 's/^/  /' || true
  journal_tail
  die $E_SERVICE "$UNIT failed to start on $host: $1 (journal above)"
}
[[ -z ${restart_failed:-} ]] || { sed 's/^/  /' "$tmp/restart.out"; service_failed "systemctl restart failed"; }

# A daemon that rejects its config exits at once; Restart= may bring it back
# up in between, so the restart counter and the main exit status also count.
get() { sed -n "s/^$1=//p" <<<"$state"; }
deadline=$(($(date +%s) + settle_s))
while :; do
  state=$(remote "systemctl show -p ActiveState -p SubState -p NRestarts -p ExecMainStatus $UNIT")
  active=$(get ActiveState) sub=$(get SubState) restarts=$(get NRestarts) status=$(get ExecMainStatus)
  if [[ $active == failed || $sub == auto-restart || $sub == dead || ${restarts:-0} -gt ${restarts_before:-0} ]]; then
    service_failed "state $active/$sub, last exit status ${status:-?}, $((restarts - restarts_before)) automatic restart(s)"
  fi
  (($(date +%s) < deadline)) || break
  sleep 0.5
done
[[ $active == active && $sub == running ]] || service_failed "state $active/$sub after ${settle_s} s"
echo "--- systemctl status $UNIT ---"
remote "$sudo systemctl status $UNIT --no-pager -l -n 5" 2>&1 | sed 's/^/  /' || true

# --- 5. the first diagnostics message ----------------------------------------
# decode_diagnostics check|print: the daemon's first message and, when that
# one is from before the loop's first tick, the first from the running loop.
# Exit 0 once a message from the running loop is there, 3 before.
read -r -d '' DECODE <<'PY' || true
import os, sys
sys.path.insert(0, os.path.join(os.environ["RTFUSE_REPO"], "tools"))
from rtfuse_tools.lcm_log import LogReader, LcmLogError
from rtfuse_tools.lcmtypes_path import import_lcmtypes

mode, path, channel, restart = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
rtfuse = import_lcmtypes()
try:
    with LogReader(path, allow_truncated_tail=True) as r:
        events = list(r)
    msgs = [(e.timestamp, rtfuse.diagnostics_t.decode(e.data)) for e in events]
except (LcmLogError, ValueError) as e:
    sys.exit(f"{channel}: cannot decode a diagnostics_t message: {e}")
running = next((m for m in msgs if m[1].loop.ticks > 0), None)
if mode == "check" or not msgs:
    sys.exit(0 if running else 3)
LEVEL = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}


def show(title, stamp, d):
    l = d.loop
    print(f"--- {title} (received {stamp / 1e6 - restart:.1f} s after the restart) ---")
    print(f"  seq {d.header.seq}: loop {l.rate_hz:.1f} Hz (period {l.period_ns / 1e6:.3f} ms), {l.ticks} ticks, "
          f"{l.overruns} overruns, jitter mean {l.jitter_mean_ns / 1e3:.0f} us max {l.jitter_max_ns / 1e3:.0f} us, "
          f"tick mean {l.tick_duration_mean_ns / 1e3:.0f} us max {l.tick_duration_max_ns / 1e3:.0f} us, "
          f"{l.measurements_fused} measurements fused")
    for s in d.sensors:
        rejected = (s.rejected_mahalanobis + s.rejected_invalid + s.rejected_stale
                    + s.rejected_overflow + s.rejected_rate + s.rejected_oversize + s.decode_errors)
        print(f"  sensor {s.name}: {LEVEL.get(s.level, s.level)}, {s.rate_hz:.1f} Hz, received {s.received}, "
              f"accepted {s.accepted}, rejected {rejected}, timeouts {s.timeouts}")
    for dev in d.devices:
        values = ", ".join(f"{k} {v}" for k, v in zip(dev.keys, dev.values))
        print(f"  device {dev.name} ({dev.hardware_id}): {LEVEL.get(dev.level, dev.level)} {dev.state}"
              + (f", {values}" if values else "") + (f"; last error: {dev.message}" if dev.message else ""))


show(f"first {channel} message", *msgs[0])
if running and running is not msgs[0]:
    show(f"first {channel} message from the running loop", *running)
sys.exit(0 if running else 3)
PY
decode_diagnostics() {
  RTFUSE_REPO=$REPO "$PYTHON" -c "$DECODE" "$1" "$diag_log" "$diag_channel" "$restart_time"
}

if ((diag_rate <= 0)); then
  say "warning: [publish] diagnostics_rate = $diag_rate: the daemon publishes no diagnostics, not waiting"
else
  say "waiting up to ${timeout_s} s for $diag_channel on $lcm_url"
  [[ -z $build_dir || ! -f $build_dir/lcmtypes/python/rtfuse/__init__.py ]] ||
    export RTFUSE_LCMTYPES_PYTHON=$build_dir/lcmtypes/python
  end=$(($(date +%s) + timeout_s))
  while (($(date +%s) < end)); do
    kill -0 "$logger_pid" 2>/dev/null || {
      sed 's/^/  lcm-logger: /' "$tmp/logger.out" >&2
      die $E_DIAG "lcm-logger cannot listen on $lcm_url (no multicast route? ip route add 224.0.0.0/4 dev IFACE)"
    }
    sleep 0.5
    if [[ -s $diag_log ]]; then
      status=0
      decode_diagnostics check || status=$?
      ((status == 3)) || break
    fi
  done
  kill -INT "$logger_pid" 2>/dev/null || true  # lcm-logger closes its file on SIGINT
  wait "$logger_pid" 2>/dev/null || true
  logger_pid=''
  if [[ ! -s $diag_log ]]; then
    remote "$sudo systemctl is-active $UNIT" >/dev/null 2>&1 || journal_tail
    die $E_DIAG "no $diag_channel message on $lcm_url within ${timeout_s} s (the daemon's url is $daemon_url)"
  fi
  status=0
  decode_diagnostics print || status=$?
  ((status != 3)) || die $E_DIAG "$diag_channel arrives, but the daemon's loop did not tick within ${timeout_s} s"
  ((status == 0)) || die $E_DIAG "cannot decode the $diag_channel messages"
fi

say "done: $pkg_name on $host ($arch), $UNIT running, in $(elapsed "$start_time") s"
