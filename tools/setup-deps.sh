#!/usr/bin/env bash
# Installs the Debian 12 packages rtfuse builds, tests and runs with, skipping
# what is already there (so a set-up machine does no apt work at all).
set -euo pipefail

packages=(
  gcc g++ cmake ninja-build make
  libeigen3-dev
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java
  libtomlplusplus-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  default-jdk-headless
  python3 python3-rosbag python3-yaml python3-matplotlib
  # ROS message classes for the bags the integration tests write (test only)
  python3-sensor-msgs python3-nav-msgs
  iproute2 util-linux
  linux-libc-dev libgpiod-dev
  # the stereo PNG writer of the snapshot tool (src/apps/stereo_png.cpp)
  libpng-dev
  # map_server YAML files (src/apps/map_server_map.cpp: rtfuse-plan loads maps)
  libyaml-cpp-dev
  # XXH64, inlined (the camera's digest of its rectified pairs, src/core/xxh64.hpp)
  libxxhash-dev
  # PCG32, header-only: the visual odometry's deterministic RANSAC (src/vision)
  libpcg-cpp-dev
  binutils libc6-dev
  # the aarch64 stage (tools/test-cross.sh): cross compiler, user-mode
  # emulation, and the arm64 package installed in a clean arm64 root
  g++-aarch64-linux-gnu qemu-user qemu-user-static binfmt-support debootstrap file
  # the package test (tests/package): systemd-analyze verify of the unit
  systemd
  # tools/deploy.sh (ssh), and its test (tests/deploy) boots a board with
  # systemd-nspawn from a debootstrap root
  openssh-client systemd-container
  # the kernel system test (tests/kernel) boots Debian's own kernel under
  # qemu with a busybox initramfs and runs the Linux backends on its drivers
  qemu-system-x86 busybox-static cpio kmod
  # the AddressSanitizer tree and the fuzz harnesses (tools/asan_tree.sh,
  # tools/fuzz.sh): clang, its sanitizer and libFuzzer runtimes, and
  # llvm-symbolizer for the stack traces of a finding
  clang libclang-rt-dev llvm
  # the stereo rectification's reference in the test build (tests/reference);
  # never linked into the runtime
  libopencv-dev
  # the geodesy's reference in the test build (tests/reference): the
  # GeographicLib robot_localization projects with; never linked into the
  # runtime (src/estimation/geodesy.hpp says why)
  libgeographiclib-dev
  # the occupancy map's reference in the test build (tests/reference and its
  # benchmark): OctoMap's own maps and .bt files; never linked into the runtime
  liboctomap-dev
  # OctoMap's scan.dat comes bzip2-compressed (tests/reference reads it)
  bzip2
  # the grid planner's reference in the test build (tests/reference and its
  # benchmark): Boost Graph's Dijkstra and A* on the same graph; header-only
  # here, never linked into the runtime
  libboost-graph-dev
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "rtfuse: installing missing packages: ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  SUDO=sudo
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
