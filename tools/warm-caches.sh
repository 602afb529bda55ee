#!/usr/bin/env bash
# warm-caches.sh [--no-cross]: makes the caches the slow tests reuse, so that
# tools/test.sh can make them beside the native build instead of inside the
# test stages: the clean amd64 Debian root the package test installs into,
# the deploy test's board root, and (unless --no-cross) the arm64 sysroot
# and the clean arm64 root of the aarch64 stage. Each is mostly downloading
# and unpacking (debootstrap; the arm64 root's second stage runs under
# qemu), each is made once and reused, and each maker holds a lock, so a
# test that starts while it is being made waits for it rather than making
# it twice. Needs root and the packages of tools/setup-deps.sh; without
# root it does nothing (the tests then skip, as they say).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cross=1
[[ ${1:-} == --no-cross ]] && cross=0
[[ $(id -u) -eq 0 ]] || { echo "warm-caches: not root, nothing to make"; exit 0; }

# A cache that cannot be made here is the test's to make, and to fail on
# with its own words: this only saves time.
stage() {
  local start=$SECONDS rc=0
  "$@" || rc=$?
  echo >&2 "warm-caches: '$*' took $((SECONDS - start)) s$( ((rc == 0)) || echo " and failed (exit $rc): the test makes it itself")"
}
# The paths the tests use: tests/package/CMakeLists.txt (RTFUSE_PACKAGE_ROOTS,
# per tree) and tests/deploy/run_deploy_test.sh (CACHE, per tree).
mkdir -p "$root/build/test"
stage "$root/tests/package/make_root.sh" amd64 "$root/build/test/package-roots/bookworm-amd64" >/dev/null
stage "$root/tests/deploy/run_deploy_test.sh" "$root/build/test" "$root/build/test/tests/deploy/out" PREPARE_ONLY=1 >/dev/null
if ((cross)); then
  stage "$root/tools/make-sysroot.sh" "$root/build/sysroot-arm64" >/dev/null
  mkdir -p "$root/build/aarch64"
  stage "$root/tests/package/make_root.sh" arm64 "$root/build/aarch64/package-roots/bookworm-arm64" >/dev/null
fi
