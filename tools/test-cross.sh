#!/usr/bin/env bash
# test-cross.sh [ctest args]: the aarch64 stage of the test command.
#
# Builds a stand-in Jetson sysroot from Debian 12 arm64 packages
# (tools/make-sysroot.sh), cross-builds the programs and the unit tests with
# toolchains/aarch64-jetson-tx2.cmake, runs the unit tests under qemu-aarch64
# with the sysroot as the loader's root, replays recordings across the two
# architectures, installs the arm64 package in a clean arm64 root, and
# shows what the target-ABI check
# says about the aarch64 programs. Called by tools/test.sh after the native
# tests; runs alone after tools/setup-deps.sh.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sysroot="$root/build/sysroot-arm64"
dir="$root/build/aarch64"
# --build-only: the sysroot and the aarch64 tree, no tests (tools/test.sh
# builds it while earlier stages test).
build_only=0
if [[ ${1:-} == --build-only ]]; then
  build_only=1
  shift
fi

"$root/tools/make-sysroot.sh" "$sysroot"
# The native programs, for the cross-architecture replay test (a no-op after
# tools/test.sh's native stage).
"$root/tools/build.sh" test

start=$(date +%s)
# Configured every time (a second or so, nothing rebuilt when unchanged), so a
# tree made by hand also gets the native programs for the cross-arch test.
# Line tables only (-g1): backtraces keep their file and line, and the
# compiler does a third less work than for full debug info. No benchmarks:
# their aarch64 figures come from tools/bench-emulated.sh, not from CI.
cmake -S "$root" -B "$dir" -G Ninja \
  -DCMAKE_TOOLCHAIN_FILE="$root/toolchains/aarch64-jetson-tx2.cmake" \
  -DRTFUSE_SYSROOT="$sysroot" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1" \
  -DRTFUSE_BUILD_TESTS=ON -DRTFUSE_BUILD_BENCH=OFF -DRTFUSE_EIGEN_NO_MALLOC_CHECK=ON -DRTFUSE_WERROR=ON \
  -DRTFUSE_NATIVE_APPS_DIR="$root/build/test/src/apps" >/dev/null
# What this stage runs, and only that: the unit tests, and what the package
# holds (its programs are the ones the cross-architecture replay runs).
targets=(rtfuse_deb_inputs)
for layer in core hal drivers geometry vision estimation mapping navigation transport runtime sim apps; do
  targets+=("rtfuse_unit_$layer")
done
cmake --build "$dir" -j"$(nproc)" --target "${targets[@]}"
echo "test-cross: aarch64 build took $(($(date +%s) - start)) s"
((build_only)) && exit 0

apps=("$dir/src/apps/rtfused" "$dir/src/apps/rtfuse-replay" "$dir/src/apps/rtfuse-sim")

# The ABI check, shown in full. Against the stand-in (Debian 12, glibc 2.36)
# the programs must load: nothing newer than 2.36, and no libstdc++ or libgcc
# symbol versions at all (linked statically). Against a stock JetPack 4.6 TX2
# (glibc 2.27) the same programs ask for GLIBC_2.34 and later, because the
# stand-in's glibc is newer: the report lists them; a build against the real
# L4T rootfs is what passes there (README, "Deploy to a Jetson").
echo "test-cross: target ABI of the aarch64 programs"
file "${apps[@]}" 2>/dev/null || true
"$root/tools/check-target-abi.sh" "${apps[@]}" --glibc 2.36 --glibcxx 3.4.0 --gcc 3.0
echo "test-cross: the same programs against a stock TX2 (JetPack 4.6, glibc 2.27), expected to fail with this sysroot:"
if "$root/tools/check-target-abi.sh" "${apps[@]}" --glibc 2.27; then
  echo "test-cross: unexpected: nothing newer than glibc 2.27 although built against 2.36" >&2
  exit 1
fi

cd "$dir"
# What the emulation proves, and only that: the unit tests on the target's
# instruction set (every layer's arithmetic, the SIMD paths on NEON), the
# recordings crossing the two architectures both ways (integration_cross_arch_*,
# label cross_arch: every output byte-identical), and the arm64 package in a
# clean arm64 root. The other integration and system tests replay, drive and
# publish through the same code the unit tests and the cross-architecture
# replay already run on aarch64; they run natively (tools/test.sh's first
# stage) and under the sanitizers.
# Left out here, each run by the native stage:
# - qemu-user's termios translation has no B921600: the emulator hands the
#   kernel another rate and the serial backend rightly refuses the port. Not
#   the target's behaviour (an arm64 kernel has the rate).
# - the simulated camera's two lockstep drives (rendering and rectifying
#   every frame: 206 s of test time under emulation, the longest after the
#   package install): the arithmetic they exercise is integer, and
#   integration_cross_arch_frames replays a drive with frames across the two
#   architectures, every rectified pair compared, which is what this stage
#   is for.
# - the slow second frame consumer (a minute under emulation, the longest
#   unit test there): what it proves is about threads (a consumer that
#   cannot keep up drops pairs, counted, and neither capture nor the
#   odometry waits for it), not about the instruction set; it runs natively
#   and under ASan, and the odometry's arithmetic on aarch64 is the cross-
#   architecture replay's.
# - the map's accuracy on the simulated obstacle course (35 to 345
#   rendered pairs a scoring, their disparity and the map: seconds
#   natively, minutes emulated): it scores depth against the world's
#   truth; the matcher's and the map's bits on aarch64 are their own unit
#   tests' (backends agree, digests).
# - the mapper's lockstep drive and its replay (rendering and keyframes: a
#   minute or more emulated): the map on aarch64 is the cross-architecture
#   replay's, which compares its digest with the x86-64 one.
# - the navigator's closed loop and its replay, and its whole obstacle
#   course (30 s and 65 s of camera, map and plans natively, many minutes
#   emulated): the navigator's own arithmetic
#   on aarch64 is its unit tests' (the same commands whenever its thread
#   runs, the planner's pinned digest).
ctest --output-on-failure -j2 -L 'unit|package|cross_arch' \
  -E '^(HalTermiosSerialPort\.EveryStandardRateIsSetAndReadBack|SimCamera\.LockstepDriveRectifiesEveryFrameAtTheConfiguredRate|SimCamera\.RecordedFramesReplayThroughTheDriver|FrameConsumers\.ASlowSecondConsumerDropsPairsButNeverStallsCaptureOrChangesTheOdometry|SimMapAccuracy\..*|MapperDrive\.LockstepDriveMapsEveryKeyframeAndItsRecordingReplaysTheSameMap|NavDrive\.FindsTheWallInItsOwnMapGoesRoundAndItsRecordingReplays|NavDrive\.TheObstacleCoursesTenGoalsEachReachedWithin30CmOfTheTruth)$' "$@"
