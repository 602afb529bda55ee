#!/usr/bin/env bash
# kernel_vm.sh --cache DIR --modules "M1 M2..." [--module-args "M ARG..."]...
#              [--timeout SEC] [--out DIR] -- COMMAND [ARG]...
#
# Runs COMMAND on Debian 12's own kernel (linux-image-amd64) under
# qemu-system-x86_64, against real kernel drivers this machine's kernel does
# not have (vivid, vcan, i2c-stub, ...). The guest sees the host's root
# read-only over virtio-9p and runs COMMAND chrooted into it, so the host's
# own binaries and libraries run unchanged on the guest kernel. Prints
# COMMAND's output and returns its exit code.
#
#   1. fetch: `apt-get download` of the kernel package once, unpacked with
#      dpkg-deb and given a modules.dep (depmod -b) in the cache; later runs
#      use the cache and need no network.
#   2. initramfs: busybox-static, the 9p modules and the requested modules
#      with their dependencies (from modules.dep, loaded in dependency order).
#   3. boot under TCG (KVM does not work in every VM): the guest's /init loads
#      the modules, mounts the host root on /host with /proc, /sys, /dev
#      (devtmpfs) and a tmpfs /run over it, mounts the run directory writable
#      at the same path it has on the host (TMPDIR points into it: the rest
#      of the host root, /tmp included, is read-only), chroots and runs
#      COMMAND there.
#   4. COMMAND's output and exit code come back through the run directory.
#
# The guest has no network (-nic none). Several runs may share one cache
# (a lock guards the fetch); each run has its own run directory.
#
# Exit codes: COMMAND's own, or
#   77  skipped: not root, or qemu-system-x86_64 / busybox-static missing
#   100 usage error
#   101 a host tool is missing (apt-get, dpkg-deb, depmod, cpio, gzip, timeout)
#   102 the kernel package cannot be resolved, downloaded or unpacked
#   103 a requested module is not in that kernel
#   104 the guest did not finish in time (boot or COMMAND hung; see console)
#   105 the guest ended without a result (panic, 9p mount or chroot failed)
#   106 a requested module failed to load in the guest (insmod error shown)
# (COMMAND exit codes 100..106 cannot be told apart from these.)
#
# Environment:
#   RTFUSE_KERNEL_PACKAGE  kernel package to use (default: the one in the
#                          cache, else the one linux-image-amd64 depends on)
#   RTFUSE_KERNEL_VM_ACCEL=kvm  use KVM where it works (default tcg)
#   RTFUSE_KERNEL_VM_KEEP=1  keep the run directory (console log, initramfs);
#                          it is always kept after codes 104..106
set -euo pipefail

EX_SKIP=77 EX_USAGE=100 EX_TOOL=101 EX_PACKAGE=102 EX_MODULE=103
EX_TIMEOUT=104 EX_NORESULT=105 EX_MODLOAD=106
t_begin=$(date +%s.%N)

say() { echo "kernel_vm: $*" >&2; }
die() {
  local code=$1
  shift
  say "FAIL: $*"
  exit "$code"
}
usage() {
  sed -n '2,4p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit $EX_USAGE
}

cache= modules=() out= timeout_s=240
declare -A module_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --cache) cache=${2:?}; shift 2 ;;
    --modules) read -r -a more <<<"${2?}"; modules+=("${more[@]}"); shift 2 ;;
    --module-args)
      read -r name rest <<<"${2:?}"
      module_args[${name//-/_}]=$rest
      shift 2 ;;
    --timeout) timeout_s=${2:?}; shift 2 ;;
    --out) out=${2:?}; shift 2 ;;
    --) shift; break ;;
    -h | --help) usage ;;
    *) say "unknown option '$1'"; usage ;;
  esac
done
[[ -n "$cache" && $# -gt 0 ]] || usage
[[ "$timeout_s" =~ ^[0-9]+$ ]] || die $EX_USAGE "--timeout wants seconds, got '$timeout_s'"

# --- prerequisites ----------------------------------------------------------
if [[ $(id -u) -ne 0 ]]; then
  # apt-get download works as anyone, but the 9p share of / must read every
  # file the command needs and the guest writes its results as root.
  echo "SKIP: kernel_vm.sh needs root (the guest reads the host root over 9p as qemu's user)"
  exit $EX_SKIP
fi
qemu=$(command -v qemu-system-x86_64 || true)
[[ -n "$qemu" ]] || { echo "SKIP: qemu-system-x86_64 not installed (apt-get install qemu-system-x86)"; exit $EX_SKIP; }
busybox=/bin/busybox
if ! [[ -x $busybox ]]; then
  echo "SKIP: $busybox missing (apt-get install busybox-static)"
  exit $EX_SKIP
fi
if ldd "$busybox" >/dev/null 2>&1; then
  die $EX_TOOL "$busybox is dynamically linked; the initramfs needs busybox-static (apt-get install busybox-static)"
fi
for tool in apt-get apt-cache dpkg-deb depmod cpio gzip timeout flock; do
  command -v "$tool" >/dev/null || die $EX_TOOL "'$tool' not found (tools/setup-deps.sh installs what the kernel tests need)"
done
depmod=$(command -v depmod)

mkdir -p "$cache"
cache=$(cd "$cache" && pwd)

# --- 1. the kernel package, fetched once -------------------------------------
resolve_package() {
  # The metapackage names the current ABI; its own .deb holds no kernel.
  apt-cache depends linux-image-amd64 2>/dev/null |
    awk '$1 == "Depends:" && $2 ~ /^linux-image-[0-9].*-amd64(-unsigned)?$/ { print $2; exit }'
}

# The bzImage decompresses itself (xz) before the kernel's clock starts:
# ~6 s under TCG on every boot. The ELF inside carries a PVH entry note
# (CONFIG_PVH), which qemu boots directly. Extracted once; without xz or the
# note the bzImage is booted as it is.
extract_pvh() {
  local bz=$1 elf=$2 off
  command -v xz >/dev/null && command -v readelf >/dev/null || return 0
  off=$(LC_ALL=C grep -abo $'\xfd7zXZ\x00' "$bz" | head -1 | cut -d: -f1)
  [[ -n "$off" ]] || return 0
  tail -c +$((off + 1)) "$bz" | xz -dc >"$elf.tmp" 2>/dev/null || true  # trailing data after the stream
  # XEN_ELFNOTE_PHYS32_ENTRY (18): the PVH entry point.
  if readelf -n "$elf.tmp" 2>/dev/null | grep -q 'Xen.*(0x00000012)'; then
    mv "$elf.tmp" "$elf"
  else
    rm -f "$elf.tmp"
  fi
}

# A fresh CI image may carry no package lists: fetch them once, then retry.
apt_updated=0
apt_update_once() {
  ((apt_updated == 0)) || return 1
  apt_updated=1
  say "apt knows no such package yet: running apt-get update once"
  apt-get update -qq >&2 || say "apt-get update failed"
  return 0
}

# Unpacks into DIR/<package>/ (boot/vmlinuz-*, lib/modules/<version>/ with
# modules.dep). The tree is complete once DIR/<package>/.complete exists.
fetch_kernel() {
  local pkg=$1 dest=$cache/$pkg
  [[ -f $dest/.complete ]] && return 0
  local tmp
  tmp=$(mktemp -d "$cache/.fetch.XXXXXX")
  say "downloading $pkg (once; cached in $cache)"
  # apt drops privileges to _apt for downloads into a directory _apt can
  # write; a private temp directory is fine for root and only warns.
  if ! (cd "$tmp" && apt-get download "$pkg") >"$tmp/apt.log" 2>&1 &&
    ! { apt_update_once && (cd "$tmp" && apt-get download "$pkg") >"$tmp/apt.log" 2>&1; }; then
    cat "$tmp/apt.log" >&2
    rm -rf "$tmp"
    die $EX_PACKAGE "cannot download kernel package '$pkg' (is 'apt-get update' done and the Debian mirror reachable?)"
  fi
  local deb
  deb=$(ls "$tmp"/*.deb)
  if ! dpkg-deb -x "$deb" "$tmp/root"; then
    rm -rf "$tmp"
    die $EX_PACKAGE "cannot unpack $deb with dpkg-deb"
  fi
  local version
  version=$(ls "$tmp/root/lib/modules" 2>/dev/null | head -1)
  if [[ -z "$version" || ! -f "$tmp/root/boot/vmlinuz-$version" ]]; then
    rm -rf "$tmp"
    die $EX_PACKAGE "$pkg holds no boot/vmlinuz-* with lib/modules/*: not a kernel image package"
  fi
  # Debian's package ships no modules.dep (the postinst runs depmod).
  if ! "$depmod" -b "$tmp/root" "$version"; then
    rm -rf "$tmp"
    die $EX_PACKAGE "depmod -b $tmp/root $version failed"
  fi
  rm -rf "$tmp/root/usr" "$deb" "$tmp/apt.log"
  echo "$version" >"$tmp/root/.version"
  touch "$tmp/root/.complete"
  rm -rf "$dest"
  mv "$tmp/root" "$dest"
  rm -rf "$tmp"
  # One kernel per cache: older ABIs are dead weight (~400 MB each).
  local old
  for old in "$cache"/linux-image-*; do
    [[ "$old" != "$dest" && -d "$old" ]] && rm -rf "$old"
  done
  return 0
}

exec 9>"$cache/.lock"
flock 9
# A cached kernel is used as it is (no apt at all: offline, reproducible, and
# apt-cache alone costs seconds); remove the cache to move to a newer one.
pkg=${RTFUSE_KERNEL_PACKAGE:-}
if [[ -z "$pkg" ]]; then
  cached=$(ls -d "$cache"/linux-image-*/.complete 2>/dev/null | sort -V | tail -1 || true)
  [[ -n "$cached" ]] && pkg=$(basename "$(dirname "$cached")")
fi
[[ -n "$pkg" ]] || pkg=$(resolve_package)
[[ -n "$pkg" ]] || { apt_update_once && pkg=$(resolve_package); }
[[ -n "$pkg" ]] || die $EX_PACKAGE "cannot resolve the kernel package: 'apt-cache depends linux-image-amd64' names none (run 'apt-get update', or set RTFUSE_KERNEL_PACKAGE=linux-image-<abi>-amd64)"
fetch_kernel "$pkg"
kroot=$cache/$pkg
kver=$(cat "$kroot/.version")
kmods=$kroot/lib/modules/$kver
vmlinuz=$kroot/boot/vmlinuz-$kver
if [[ ! -f $kroot/boot/vmlinux-$kver && ! -f $kroot/.no-pvh ]]; then
  extract_pvh "$vmlinuz" "$kroot/boot/vmlinux-$kver"
  [[ -f $kroot/boot/vmlinux-$kver ]] || touch "$kroot/.no-pvh"
fi
[[ -f $kroot/boot/vmlinux-$kver ]] && vmlinuz=$kroot/boot/vmlinux-$kver
flock -u 9

# --- 2. modules in dependency order ------------------------------------------
# modules.dep: "kernel/path/name.ko: dep1.ko dep2.ko ..." with each line's
# dependencies listed in full (transitively), deepest last.
declare -A mod_path=() mod_deps=() builtin=()
while IFS= read -r line; do
  path=${line%%:*}
  base=${path##*/}
  name=${base%%.ko*}
  name=${name//-/_}
  mod_path[$name]=$path
  mod_deps[$name]=${line#*:}
done <"$kmods/modules.dep"
while IFS= read -r path; do
  base=${path##*/}
  name=${base%%.ko*}
  builtin[${name//-/_}]=1
done <"$kmods/modules.builtin"

order=()
declare -A placed=()
place() {
  local name=$1 dep d
  [[ -n "${placed[$name]:-}" ]] && return 0
  placed[$name]=1
  local deps=(${mod_deps[$name]})
  # Deepest dependency last in the line: load from the end.
  for ((d = ${#deps[@]} - 1; d >= 0; d--)); do
    dep=${deps[d]##*/}
    dep=${dep%%.ko*}
    place "${dep//-/_}"
  done
  order+=("$name")
}
# virtio-9p for the host root and the run directory, then what was asked.
for m in virtio_pci 9pnet_virtio 9p "${modules[@]}"; do
  m=${m//-/_}
  if [[ -n "${mod_path[$m]:-}" ]]; then
    place "$m"
  elif [[ -z "${builtin[$m]:-}" ]]; then
    die $EX_MODULE "module '$m' is not in kernel $kver (not in $kmods/modules.dep nor modules.builtin)"
  fi
done
for m in "${!module_args[@]}"; do
  [[ -n "${placed[$m]:-}" ]] || say "note: --module-args for '$m', which is built in or not requested: ignored"
done

# --- 3. run directory and initramfs -----------------------------------------
if [[ -z "$out" ]]; then
  out=$(mktemp -d "$cache/run.XXXXXX")
  # Kept when the guest failed (console log, dmesg, initramfs to look at).
  [[ "${RTFUSE_KERNEL_VM_KEEP:-0}" == 1 ]] || trap 'rc=$?; ((rc >= EX_TIMEOUT && rc <= EX_MODLOAD)) || rm -rf "$out"' EXIT
else
  rm -rf "$out"
  mkdir -p "$out"
fi
out=$(cd "$out" && pwd)
initdir=$out/initramfs
mkdir -p "$initdir"/{bin,dev,proc,sys,host,modules}
cp "$busybox" "$initdir/bin/busybox"

# Module load list for /init: "file args..." per line, in order.
: >"$initdir/modules/load"
for name in "${order[@]}"; do
  file=${mod_path[$name]##*/}
  cp "$kmods/${mod_path[$name]}" "$initdir/modules/$file"
  echo "$file ${module_args[$name]:-}" >>"$initdir/modules/load"
done

# The command, quoted by bash for bash (the host's, inside the chroot).
{
  echo "cd $(printf '%q' "$PWD") 2>/dev/null || cd /"
  printf 'exec'
  printf ' %q' "$@"
  echo
} >"$out/command.sh"

cat >"$initdir/init" <<EOF
#!/bin/busybox sh
# Generated by tests/kernel/kernel_vm.sh: load modules, mount the host root,
# run the command chrooted into it, write its exit code, power off.
/bin/busybox --install -s /bin
export PATH=/bin
run=$(printf '%q' "$out")
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
echo "rtfuse-vm: init at \$(cut -d' ' -f1 /proc/uptime) s"
fail=""
while read -r file args; do
  if ! err=\$(insmod "/modules/\$file" \$args 2>&1); then
    echo "rtfuse-vm: insmod \$file \$args failed: \$err"
    fail="\$fail \$file"
  fi
done </modules/load
mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144,ro host /host ||
  { echo "rtfuse-vm: cannot mount the host root (9p tag 'host')"; poweroff -f; }
mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144 results "/host\$run" ||
  { echo "rtfuse-vm: cannot mount the run directory (9p tag 'results')"; poweroff -f; }
if [ -n "\$fail" ]; then
  echo "\$fail" >"/host\$run/modules-failed"
  dmesg | tail -20 >"/host\$run/dmesg"
  sync
  poweroff -f
fi
mount -t proc proc /host/proc
mount -t sysfs sysfs /host/sys
mount -t devtmpfs devtmpfs /host/dev
mkdir -p /host/dev/shm
mount -t tmpfs tmpfs /host/dev/shm
mount -t tmpfs tmpfs /host/run
mkdir -p "/host\$run/tmp"
dmesg >"/host\$run/dmesg-boot"
echo "\$(cut -d' ' -f1 /proc/uptime)" >"/host\$run/started"
echo "rtfuse-vm: command at \$(cut -d' ' -f1 /proc/uptime) s"
chroot /host /usr/bin/env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  HOME=/root LANG=C.UTF-8 TERM=dumb TMPDIR="\$run/tmp" RTFUSE_IN_KERNEL_VM=1 \
  /bin/bash "\$run/command.sh" >"/host\$run/output" 2>&1
echo \$? >"/host\$run/exit_code"
echo "\$(cut -d' ' -f1 /proc/uptime)" >"/host\$run/finished"
dmesg >"/host\$run/dmesg"
sync
umount "/host\$run"
poweroff -f
EOF
chmod +x "$initdir/init"
initrd=$out/initramfs.cpio.gz
(cd "$initdir" && find . | cpio -o -H newc --quiet | gzip -1) >"$initrd" ||
  die $EX_TOOL "cannot build the initramfs in $initdir"

# --- 4. boot ------------------------------------------------------------------
# TCG by default: /dev/kvm may exist in a VM whose KVM does not work.
accel=${RTFUSE_KERNEL_VM_ACCEL:-tcg}
cpu=qemu64
[[ $accel == kvm ]] && cpu=host
say "booting $pkg ($kver) with modules: ${order[*]}"
t0=$(date +%s.%N)
set +e
timeout --kill-after=10 "$timeout_s" "$qemu" \
  -accel "$accel" -cpu "$cpu" -m 1024 -smp 1 \
  -display none -monitor none -serial "file:$out/console.log" \
  -no-reboot -nic none \
  -kernel "$vmlinuz" -initrd "$initrd" \
  -append "console=ttyS0 panic=-1 quiet" \
  -virtfs local,path=/,mount_tag=host,security_model=none,readonly=on,multidevs=remap \
  -virtfs "local,path=$out,mount_tag=results,security_model=none,multidevs=remap" \
  </dev/null >"$out/qemu.log" 2>&1
qemu_rc=$?
set -e
t1=$(date +%s.%N)

show_console() {
  say "---- guest console (last 40 lines of $out/console.log) ----"
  tail -40 "$out/console.log" >&2 || true
  [[ -s "$out/qemu.log" ]] && { say "---- qemu ----"; cat "$out/qemu.log" >&2; }
  return 0
}

if [[ -f "$out/output" ]]; then
  cat "$out/output"
fi
if [[ $qemu_rc -eq 124 || $qemu_rc -eq 137 ]]; then
  show_console
  die $EX_TIMEOUT "the guest did not finish within ${timeout_s}s (boot or the command hung); run dir $out"
fi
if [[ -f "$out/modules-failed" ]]; then
  show_console
  [[ -f "$out/dmesg" ]] && { say "---- guest dmesg ----"; cat "$out/dmesg" >&2; }
  die $EX_MODLOAD "module(s)$(cat "$out/modules-failed") failed to load in kernel $kver (see the insmod lines above)"
fi
if [[ ! -f "$out/exit_code" ]]; then
  show_console
  die $EX_NORESULT "the guest ended without a result (qemu exit $qemu_rc); run dir $out"
fi
rc=$(cat "$out/exit_code")
started=$(cat "$out/started" 2>/dev/null || echo "?")
finished=$(cat "$out/finished" 2>/dev/null || echo "?")
say "$(awk -v p="$t_begin" -v a="$t0" -v b="$t1" -v s="$started" -v f="$finished" 'BEGIN {
  printf "preparation %.1f s, qemu %.1f s (guest uptime at command start %s s, command %.1f s)", a - p, b - a, s, f - s }')"
say "command exit code $rc"
exit "$rc"
