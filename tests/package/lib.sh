# shellcheck shell=bash
# Shared by the package test scripts (sourced, not run).

# die MESSAGE: a failed check.
die() { echo "FAIL: $*" >&2; exit 1; }
# skip MESSAGE: the test cannot run on this machine (CTest SKIP_RETURN_CODE 77).
skip() { echo "SKIP: $*" >&2; exit 77; }
note() { echo "-- $*" >&2; }

# deb_arch_of_machine: the Debian architecture this kernel runs natively.
host_deb_arch() {
  case "$(uname -m)" in
    x86_64) echo amd64 ;;
    aarch64) echo arm64 ;;
    i?86) echo i386 ;;
    armv7l | armv8l) echo armhf ;;
    *) echo "unknown-$(uname -m)" ;;
  esac
}

# Mounts made by mount_into are recorded here and undone by unmount_all,
# which the scripts run from an EXIT trap so a failure leaves nothing
# mounted inside a build tree.
RTFUSE_MOUNTS=()

mount_into() {  # mount_into ROOT  (proc, and the host's /dev for apt and dpkg)
  local root=$1
  mount -t proc proc "$root/proc" && RTFUSE_MOUNTS+=("$root/proc")
  mount --bind /dev "$root/dev" && RTFUSE_MOUNTS+=("$root/dev")
  if [[ -d /dev/pts ]]; then
    mount --bind /dev/pts "$root/dev/pts" && RTFUSE_MOUNTS+=("$root/dev/pts")
  fi
}

unmount_all() {
  local i
  for ((i = ${#RTFUSE_MOUNTS[@]} - 1; i >= 0; i--)); do
    umount "${RTFUSE_MOUNTS[i]}" 2>/dev/null || umount -l "${RTFUSE_MOUNTS[i]}" 2>/dev/null ||
      echo "WARNING: could not unmount ${RTFUSE_MOUNTS[i]}" >&2
  done
  RTFUSE_MOUNTS=()
}

# assert_nothing_mounted_under DIR: before deleting a root, so that rm -rf can
# never walk into the host's /dev or /proc through a leftover bind mount.
assert_nothing_mounted_under() {
  local dir
  dir=$(readlink -f "$1")
  if awk -v d="$dir/" '{ if (index($2 "/", d) == 1) found = 1 } END { exit !found }' /proc/mounts; then
    echo "FAIL: something is still mounted under $dir (see /proc/mounts); not deleting it" >&2
    exit 1
  fi
}

# ensure_emulation ARCH ROOT: make ROOT's programs runnable on this host.
# Native: nothing to do. Foreign: a binfmt_misc entry for qemu (Debian's
# qemu-user-static registers one with the F flag, so the interpreter works
# inside a chroot); mounts binfmt_misc and enables the entry where a fresh
# machine has not. Exits 77 if emulation cannot be had.
ensure_emulation() {
  local arch=$1 qarch entry
  [[ $arch == "$(host_deb_arch)" ]] && return 0
  case "$arch" in
    arm64) qarch=aarch64 ;;
    armhf) qarch=arm ;;
    *) skip "no user-mode emulation known for Debian architecture '$arch'" ;;
  esac
  entry=/proc/sys/fs/binfmt_misc/qemu-$qarch
  if [[ ! -e /proc/sys/fs/binfmt_misc/status ]]; then
    note "mounting binfmt_misc"
    mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc 2>/dev/null ||
      skip "binfmt_misc is not mounted and cannot be (mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc failed): no $arch emulation"
  fi
  if [[ ! -e $entry ]] || ! grep -qx enabled "$entry"; then
    command -v update-binfmts >/dev/null ||
      skip "no binfmt entry qemu-$qarch and no update-binfmts (apt-get install binfmt-support qemu-user-static)"
    note "enabling binfmt entry qemu-$qarch"
    update-binfmts --enable "qemu-$qarch" >/dev/null 2>&1 || true
  fi
  if [[ ! -e $entry ]] || ! grep -qx enabled "$entry"; then
    skip "binfmt entry qemu-$qarch missing or disabled and update-binfmts --enable qemu-$qarch did not help (apt-get install qemu-user-static)"
  fi
  # Without the F flag the kernel opens the interpreter inside the chroot.
  if ! grep -q '^flags:.*F' "$entry"; then
    local interp
    interp=$(awk '$1 == "interpreter" {print $2}' "$entry")
    [[ -f $interp ]] || skip "binfmt interpreter $interp of qemu-$qarch does not exist"
    if [[ -n ${2:-} ]]; then
      mkdir -p "$2$(dirname "$interp")"
      cp -L "$interp" "$2$interp"
    fi
  fi
}
