#!/usr/bin/env bash
# make_root.sh ARCH DIR [--mirror URL]
#
# A clean Debian 12 (bookworm) minbase root of architecture ARCH (amd64,
# arm64) in DIR, made by debootstrap, for installing the rtfuse package into.
# A foreign ARCH runs under qemu user-mode emulation (binfmt_misc). The root
# is a cache: a complete one (DIR/.rtfuse-root-complete) is reused as it is,
# an incomplete one (an interrupted run) is deleted and made anew. Callers
# install into a copy, never into DIR itself.
#
# Environment: RTFUSE_DEBIAN_MIRROR (default http://deb.debian.org/debian).
# Exit: 0 the root is ready (its creation time in seconds on the last line
# "root-seconds N", 0 when reused), 1 debootstrap failed, 2 usage,
# 77 cannot run here (not root, no debootstrap, no emulation for ARCH).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
source "$here/lib.sh"

usage() {
  echo "usage: $0 ARCH DIR [--mirror URL]   e.g. $0 arm64 build/package-roots/bookworm-arm64" >&2
  exit 2
}
(($# >= 2)) || usage
arch=$1 dir=$2
shift 2
mirror=${RTFUSE_DEBIAN_MIRROR:-http://deb.debian.org/debian}
while (($#)); do
  case "$1" in
    --mirror) mirror=${2:-}; [[ -n $mirror ]] || usage; shift 2 ;;
    *) echo "$0: unknown argument '$1'" >&2; usage ;;
  esac
done
[[ $arch =~ ^[a-z0-9]+$ ]] || { echo "$0: '$arch' is not a Debian architecture name" >&2; exit 2; }

[[ $(id -u) -eq 0 ]] || skip "debootstrap and chroot need root"
command -v debootstrap >/dev/null || skip "debootstrap not installed (apt-get install debootstrap)"

marker=$dir/.rtfuse-root-complete
# One maker at a time per root: tools/test.sh makes the roots beside the
# build, and a test that starts meanwhile waits here, then reuses it.
mkdir -p "$(dirname "$dir")"
exec 8>"$dir.lock"
flock 8
if [[ -f $marker ]]; then
  note "reusing the $arch root $dir ($(cat "$marker"))"
  echo "root-seconds 0"
  exit 0
fi

ensure_emulation "$arch"
if [[ -e $dir ]]; then
  note "deleting the incomplete root $dir"
  assert_nothing_mounted_under "$dir"
  rm -rf "$dir"
fi
mkdir -p "$dir"
ensure_emulation "$arch" "$dir"

# debootstrap mounts /proc and /sys in the root for its second stage and
# unmounts them itself; on an interrupted run this trap does.
cleanup() {
  local m
  for m in "$dir/proc" "$dir/sys" "$dir/dev/pts" "$dir/dev"; do
    if mountpoint -q "$m" 2>/dev/null; then umount "$m" || umount -l "$m" || true; fi
  done
}
trap cleanup EXIT

start=$(date +%s)
log=$dir.debootstrap.log
note "debootstrap --variant=minbase --arch=$arch bookworm $dir $mirror (log: $log)"
if ! debootstrap --variant=minbase --arch="$arch" bookworm "$dir" "$mirror" >"$log" 2>&1; then
  tail -n 30 "$log" >&2
  [[ -f $dir/debootstrap/debootstrap.log ]] && tail -n 30 "$dir/debootstrap/debootstrap.log" >&2
  die "debootstrap of the $arch root failed (full log: $log)"
fi
# The same archive for the deb's dependencies: apt in the root sees what
# debootstrap saw.
echo "deb $mirror bookworm main" >"$dir/etc/apt/sources.list"
echo "$arch bookworm minbase from $mirror, $(date -u +%FT%TZ)" >"$marker"
echo "root-seconds $(($(date +%s) - start))"
