#!/usr/bin/env bash
# install_test.sh DEB --source SRCDIR --roots DIR
#
# Installs the rtfuse .deb into a clean Debian 12 minbase root of the
# package's own architecture (arm64 runs under qemu user-mode emulation) with
# apt, dependencies from the mirror, and checks what a board gets:
#   - the rtfuse system user and group (no login, home /var/lib/rtfuse);
#   - the configs in /etc/rtfuse, registered as conffiles; the unit enabled
#     (multi-user.target.wants) and not started;
#   - every NEEDED library of the programs comes from a package in Depends;
#   - rtfused --version, the other programs' --help (rtfuse-replay,
#     rtfuse-sim, rtfuse-camera-snapshot, rtfuse-canopen-node), the shipped rtfused.toml loading (it then stops at
#     the missing CAN bus), a 2 s simulated run as user rtfuse, and
#     rtfuse-sim driving scenarios/straight.toml within the bounds of
#     tests/integration/sim_drives.py;
#   - systemd-analyze verify of the installed unit (and that it does catch a
#     missing ExecStart program);
#   - for a native package, the service itself under systemd in the booted
#     root (service_test.sh: user, capabilities, SCHED_FIFO, mlock, restarts);
#   - the Python types and tools with the root's python3;
#   - a reinstall keeps an edited conffile; apt-get purge removes everything.
#
# DIR caches the debootstrapped root per architecture (make_root.sh) and the
# downloaded .debs; each run installs into a fresh copy. Programs run in the
# root inside a new network namespace (unshare -n): nothing leaves the host.
# RTFUSE_KEEP_ROOT=1 keeps the copy for a look afterwards.
# Exit: 0 passed, 1 a check failed, 2 usage, 77 cannot run here (not root,
# no debootstrap, no emulation for the package's architecture).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
source "$here/lib.sh"

usage() {
  echo "usage: $0 DEB --source SRCDIR --roots DIR" >&2
  exit 2
}
deb= src= roots=
while (($#)); do
  case "$1" in
    --source) src=${2:-}; shift 2 || usage ;;
    --roots) roots=${2:-}; shift 2 || usage ;;
    -*) echo "$0: unknown option '$1'" >&2; usage ;;
    *) [[ -z $deb ]] || usage; deb=$1; shift ;;
  esac
done
[[ -n $deb && -n $src && -n $roots ]] || usage
[[ -f $deb ]] || { echo "$0: $deb: no such file (build it: cmake --build BUILD --target rtfuse_deb)" >&2; exit 2; }
deb=$(readlink -f "$deb")
[[ $(id -u) -eq 0 ]] || skip "installing into a chroot needs root"
command -v systemd-analyze >/dev/null || skip "systemd-analyze not installed (apt-get install systemd)"

arch=$(dpkg-deb -f "$deb" Architecture)
version=$(dpkg-deb -f "$deb" Version)
case "$arch" in
  amd64) triplet=x86_64-linux-gnu ;;
  arm64) triplet=aarch64-linux-gnu ;;
  *) echo "$0: no test root for architecture '$arch'" >&2; exit 2 ;;
esac
mkdir -p "$roots"
roots=$(readlink -f "$roots")
pristine=$roots/bookworm-$arch
archives=$roots/apt-archives-$arch
mkdir -p "$archives/partial"

t0=$(date +%s)
# One debootstrap per architecture at a time, whoever asks.
rc=0
mr_out=$(flock "$roots/.make_root-$arch.lock" "$here/make_root.sh" "$arch" "$pristine") || rc=$?
((rc == 0)) || exit "$rc"
root_seconds=$(awk '/^root-seconds/ {print $2}' <<<"$mr_out")
ensure_emulation "$arch"

# A copy per run: two build trees may share the cache. Copies left by a
# killed run (their process gone, nothing mounted) are deleted here, and so
# are the logs of failed runs.
for stale in "$roots/work-$arch".* "$roots/apt-$arch".*.log; do
  [[ -e $stale ]] || continue
  pid=${stale%.log}
  pid=${pid##*.}
  if [[ $pid =~ ^[0-9]+$ ]] && ! kill -0 "$pid" 2>/dev/null; then
    assert_nothing_mounted_under "$stale"
    rm -rf "$stale"
  fi
done
aptlog=$roots/apt-$arch.$$.log  # kept when a check fails
work=$roots/work-$arch.$$
cleanup() {
  local rc=$?
  unmount_all
  if ((rc != 0)) && [[ -f ${aptlog:-} ]]; then echo "apt and dpkg output: $aptlog" >&2; fi
  if [[ -d $work && ${RTFUSE_KEEP_ROOT:-0} != 1 ]]; then
    assert_nothing_mounted_under "$work"
    rm -rf "$work"
  fi
}
trap cleanup EXIT
cp -a "$pristine" "$work"
mount_into "$work"
mount --bind "$archives" "$work/var/cache/apt/archives" && RTFUSE_MOUNTS+=("$work/var/cache/apt/archives")
cp "$deb" "$work/tmp/"
debname=$(basename "$deb")

# in_root CMD...: as root in the root, no network.
in_root() { unshare -n chroot "$work" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 "$@"; }
# as_rtfuse CMD...: as the service user, no network.
as_rtfuse() { unshare -n chroot --userspec=rtfuse:rtfuse "$work" /usr/bin/env -i PATH=/usr/bin:/bin LANG=C.UTF-8 HOME=/var/lib/rtfuse "$@"; }
# apt needs the mirror: the host's network, nothing else runs like this.
apt_root() { chroot "$work" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 DEBIAN_FRONTEND=noninteractive apt-get -q -o Acquire::Retries=3 -o Dpkg::Options::=--force-unsafe-io "$@"; }

# --- install --------------------------------------------------------------
t1=$(date +%s)
apt_root update >"$aptlog" 2>&1 || { tail -20 "$aptlog" >&2; die "apt-get update in the $arch root failed"; }
apt_root install -y "/tmp/$debname" >>"$aptlog" 2>&1 ||
  { tail -30 "$aptlog" >&2; die "apt-get install /tmp/$debname failed in the clean $arch root"; }
install_seconds=$(($(date +%s) - t1))
note "installed $debname in the clean $arch root in ${install_seconds} s"
grep -E '^(Setting up|Unpacking) ' "$aptlog" | sed 's/^/   /' | grep -i rtfuse >&2 || true

[[ $(in_root dpkg-query -W -f='${Status} ${Version}' rtfuse) == "install ok installed $version" ]] ||
  die "dpkg does not list rtfuse $version as installed"

# --- user, files, unit state -----------------------------------------------
pw=$(in_root getent passwd rtfuse) || die "no user rtfuse after install"
IFS=: read -r _ _ uid gid _ home shell <<<"$pw"
((uid >= 100 && uid < 1000)) || die "rtfuse uid $uid is not a system uid (100-999): $pw"
[[ $home == /var/lib/rtfuse ]] || die "rtfuse home is $home, not /var/lib/rtfuse"
[[ $shell == */nologin || $shell == /bin/false ]] || die "rtfuse has a login shell: $shell"
[[ $(in_root getent group rtfuse | cut -d: -f3) == "$gid" ]] || die "rtfuse's primary group is not the group rtfuse"
[[ $(in_root stat -c %U /var/lib/rtfuse) == rtfuse ]] || die "/var/lib/rtfuse is not owned by rtfuse"

conffiles=$(in_root dpkg-query --control-show rtfuse conffiles)
for f in "$src"/config/*.toml "$src"/config/scenarios/*.toml "$src"/config/calibration/*.conf rtfused.toml; do
  rel=${f#"$src"/config/}
  [[ -f $work/etc/rtfuse/$rel ]] || die "/etc/rtfuse/$rel not installed"
  grep -qx "/etc/rtfuse/$rel" <<<"$conffiles" || die "/etc/rtfuse/$rel is not a conffile (dpkg-query --control-show rtfuse conffiles)"
done
cmp -s "$work/etc/rtfuse/rtfused.toml" "$src/config/robot_linux.toml" || die "/etc/rtfuse/rtfused.toml is not config/robot_linux.toml"
wants=$work/etc/systemd/system/multi-user.target.wants/rtfused.service
[[ -L $wants ]] || die "rtfused.service is not enabled ($wants missing)"
[[ $(readlink "$wants") == */rtfused.service ]] || die "$wants points to $(readlink "$wants")"

# --- libraries: each NEEDED one from a package in Depends ----------------
depends=$(in_root dpkg-query -W -f='${Depends}' rtfuse)
dep_names=$(tr ',' '\n' <<<"$depends" | sed -E 's/^ +//; s/[ (:].*//' | sort -u)
for prog in rtfused rtfuse-replay rtfuse-sim rtfuse-camera-snapshot rtfuse-canopen-node; do
  while read -r so; do
    owner=""
    for dir in "/lib/$triplet" "/usr/lib/$triplet" /lib /usr/lib; do
      [[ -e $work$dir/$so ]] || continue
      owner=$(in_root dpkg-query -S "$dir/$so" 2>/dev/null | head -n1 | cut -d: -f1) && [[ -n $owner ]] && break
    done
    [[ -n $owner ]] || die "$prog needs $so, which no installed package of the root provides"
    grep -qxF "$owner" <<<"$dep_names" ||
      die "$prog needs $so from package $owner, which is not in Depends ($depends)"
    echo "   $prog: $so <- $owner" >&2
  done < <(LC_ALL=C readelf -d -W "$work/usr/bin/$prog" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
done

# --- the programs run in the root --------------------------------------------
out=$(in_root /usr/bin/rtfused --version) || die "rtfused --version failed in the $arch root: $out"
[[ $out == "rtfused $version" ]] || die "rtfused --version printed '$out', expected 'rtfused $version'"
note "rtfused --version: $out"
for prog in rtfuse-replay rtfuse-sim rtfuse-camera-snapshot rtfuse-canopen-node; do
  in_root "/usr/bin/$prog" --help >/dev/null || die "$prog --help failed in the $arch root"
done

# The service's config loads (a config error would exit 2) and the daemon
# stops at the first missing bus, naming it.
set +e
msg=$(as_rtfuse /usr/bin/rtfused --config /etc/rtfuse/rtfused.toml --duration 1 2>&1)
rc=$?
set -e
((rc == 1)) || die "rtfused --config /etc/rtfuse/rtfused.toml as rtfuse: exit $rc (expected 1: no CAN bus here): $msg"
grep -q "can0" <<<"$msg" || die "rtfused without can0 does not name it: $msg"
note "the shipped rtfused.toml loads; without the bus: $(head -n1 <<<"$msg")"

# The simulated robot runs as the service user with the shipped configs.
msg=$(as_rtfuse /usr/bin/rtfused --config /etc/rtfuse/sim.toml --duration 2 --quiet --lcm-url memq:// 2>&1) ||
  die "rtfused --config /etc/rtfuse/sim.toml as rtfuse failed: $msg"
grep -q "ticks" <<<"$msg" || die "rtfused with sim.toml printed no summary: $msg"

# The bounds are the encoders' and the IMU's: the drive runs sim.toml without
# its camera ([camera] and [vo] up to the next [[static_transform]], and the
# odometry's [[sensor]] at the end), whose frames would cost minutes of
# rendering under emulation.
in_root sh -c "sed -e '/^\[camera\]/,/^\[\[static_transform\]\]/{/^\[\[static_transform\]\]/!d}' -e '/^# Visual odometry: the camera/,\$d' /etc/rtfuse/sim.toml > /tmp/sim_no_camera.toml" ||
  die "cannot write a camera-less copy of /etc/rtfuse/sim.toml in the $arch root"
json=$(in_root /usr/bin/rtfuse-sim -q --config /tmp/sim_no_camera.toml --scenario /etc/rtfuse/scenarios/straight.toml) ||
  die "rtfuse-sim straight.toml failed in the $arch root"
json=$(tail -n1 <<<"$json")
note "rtfuse-sim straight: $json"
# Bounds of tests/integration/sim_drives.py for straight: final 0.10 m, RMS 0.06 m.
/usr/bin/python3 - "$json" <<'EOF' || die "rtfuse-sim straight.toml: error out of bounds or bad JSON: $json"
import json, sys
r = json.loads(sys.argv[1])
ok = r["final_error_m"] <= 0.10 and r["rms_error_m"] <= 0.06
print(f"   final {r['final_error_m']:.4f} m (max 0.10), RMS {r['rms_error_m']:.4f} m (max 0.06)", file=sys.stderr)
sys.exit(0 if ok else 1)
EOF

# --- Python ------------------------------------------------------------------
pycheck='
import sys
sys.path.insert(0, "/usr/share/rtfuse/tools")
from rtfuse_tools.lcmtypes_path import find_lcmtypes_python, import_lcmtypes
d = find_lcmtypes_python()
assert str(d) == "/usr/share/rtfuse/python", d
T = import_lcmtypes()
m = T.odometry_t()
m.header.frame_id = "odom"
m.child_frame_id = "base_link"
back = T.odometry_t.decode(m.encode())
assert back.child_frame_id == "base_link", back.child_frame_id
print("rtfuse types from", d, "-", len([n for n in dir(T) if n.endswith("_t")]), "types")
'
if [[ -x $work/usr/bin/python3 ]]; then
  out=$(in_root /usr/bin/python3 -c "$pycheck" 2>&1) || die "the Python types do not import with the root's python3: $out"
  note "$out (root's python3)"
  for tool in "$src"/tools/*.py; do
    t=/usr/share/rtfuse/tools/$(basename "$tool")
    in_root "$t" --help >/dev/null 2>"$work/tmp/tool.err" || die "$t --help failed in the root: $(cat "$work/tmp/tool.err")"
  done
  note "tools --help OK: $(cd "$src/tools" && echo ./*.py)"
else
  # No python3 in the root: the installed files, with the host's python3
  # (INSTALLED_DIR is the root's, so point at it explicitly).
  out=$(cd /tmp && RTFUSE_LCMTYPES_PYTHON=$work/usr/share/rtfuse/python /usr/bin/python3 -c \
    "${pycheck//\/usr\/share/$work/usr/share}" 2>&1) || die "the installed Python types do not import: $out"
  note "$out (host python3, no python3 in the root)"
fi

# --- the unit --------------------------------------------------------------
# systemd-analyze verify --root loads the unit as the root's systemd would:
# it needs the root's own systemd units (sysinit.target, ...), so systemd is
# installed now, after every check of what the package itself pulled in.
t2=$(date +%s)
apt_root install -y --no-install-recommends systemd >>"$aptlog" 2>&1 ||
  { tail -20 "$aptlog" >&2; die "apt-get install systemd in the root failed"; }
note "systemd installed in the root for the unit check in $(($(date +%s) - t2)) s"
unit=/lib/systemd/system/rtfused.service
if ! out=$(systemd-analyze verify --root="$work" "$unit" 2>&1); then
  die "systemd-analyze verify --root=$work $unit: $out"
fi
[[ -z $out ]] || die "systemd-analyze verify warns about $unit: $out"
# The same check must see a missing program, or it proves nothing.
broken=/lib/systemd/system/rtfused-broken.service
sed 's|^ExecStart=/usr/bin/rtfused |ExecStart=/usr/bin/rtfused-missing |' "$work$unit" >"$work$broken"
if out=$(systemd-analyze verify --root="$work" "$broken" 2>&1) || ! grep -q "rtfused-missing" <<<"$out"; then
  die "systemd-analyze verify --root accepts a unit whose ExecStart does not exist ($out): the unit check is void"
fi
rm -f "$work$broken"
note "systemd-analyze verify: $unit OK (and a missing ExecStart is caught: $(head -n1 <<<"$out"))"

# --- the service under systemd ------------------------------------------
if [[ $arch == "$(host_deb_arch)" ]]; then
  unmount_all  # nspawn gives the booted root its own /proc and /dev
  "$here/service_test.sh" "$work" || die "rtfused.service does not run as it should under systemd (above)"
  mount_into "$work"
  mount --bind "$archives" "$work/var/cache/apt/archives" && RTFUSE_MOUNTS+=("$work/var/cache/apt/archives")
else
  note "not booting the $arch root: under qemu-user the unit's seccomp filter and MemoryDenyWriteExecute meet the emulator, not the board (service_test.sh runs for native packages)"
fi

# --- reinstall keeps an edited conffile; purge removes everything ------------
echo "# edited on the robot" >>"$work/etc/rtfuse/rtfused.toml"
in_root dpkg -i "/tmp/$debname" >>"$aptlog" 2>&1 || die "reinstalling $debname failed"
tail -n1 "$work/etc/rtfuse/rtfused.toml" | grep -q "edited on the robot" || die "a reinstall overwrote the edited /etc/rtfuse/rtfused.toml"

apt_root purge -y rtfuse >>"$aptlog" 2>&1 || die "apt-get purge rtfuse failed"
left=()
for p in /usr/bin/rtfused /usr/bin/rtfuse-replay /usr/bin/rtfuse-sim /etc/rtfuse /var/lib/rtfuse \
         /lib/systemd/system/rtfused.service /usr/share/rtfuse /usr/share/java/rtfuse_lcmtypes.jar \
         /etc/systemd/system/multi-user.target.wants/rtfused.service /etc/systemd/system/rtfused.service; do
  if [[ -e $work$p || -L $work$p ]]; then left+=("$p"); fi
done
((${#left[@]} == 0)) || die "apt-get purge rtfuse left: ${left[*]}"
in_root dpkg-query -W -f='${Status}' rtfuse 2>/dev/null | grep -q "not-installed" ||
  [[ -z $(in_root dpkg-query -W -f='${Status}' rtfuse 2>/dev/null) ]] || die "dpkg still knows rtfuse after purge"

rm -f "$aptlog"
total=$(($(date +%s) - t0))
echo "install_test: $debname in a clean bookworm $arch root: PASS (debootstrap ${root_seconds} s$( ((root_seconds == 0)) && echo ", cached"), apt install ${install_seconds} s, total ${total} s)"
