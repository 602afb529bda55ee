#!/usr/bin/env bash
# sanitize.sh asan|tsan [test args...]: build a sanitizer tree under build/
# and run what it checks (issue 11); sanitize.sh build asan|tsan only builds
# it (tools/test.sh builds the trees while earlier stages test):
#   asan  AddressSanitizer + UndefinedBehaviorSanitizer (clang, -O1 -g1, no
#         recovery: any finding fails its test): the unit and integration
#         tests, in the tree that also holds the fuzz harnesses
#         (tools/asan_tree.sh, tools/fuzz.sh).
#   tsan  ThreadSanitizer: the core and runtime unit tests (rings, seqlock,
#         frame pool, recorder, devices) and rtfused live on the simulated
#         robot with every sensor (encoders, IMU, camera with visual
#         odometry) for a few seconds over memq://.
# Suppressions, each with its reason, are in tests/sanitizers/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-}
shift || true
"$root/tools/setup-deps.sh"

configure_tsan() {  # dir
  if [[ ! -f "$1/build.ninja" ]]; then
    cmake -S "$root" -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
      -DRTFUSE_BUILD_TESTS=ON -DRTFUSE_BUILD_BENCH=OFF -DRTFUSE_WERROR=ON -DRTFUSE_EIGEN_NO_MALLOC_CHECK=ON \
      -DRTFUSE_SANITIZE=thread >/dev/null
  fi
}

supp="$root/tests/sanitizers"
build_tsan() {
  dir="$root/build/tsan"
  configure_tsan "$dir"
  cmake --build "$dir" -j"$(nproc)" --target rtfuse_unit_core rtfuse_unit_runtime rtfused
}
# shellcheck source=asan_tree.sh
source "$root/tools/asan_tree.sh"
if [[ $kind == build ]]; then
  case "${1:-}" in
    asan) configure_asan_tree; cmake --build "$asan_tree" -j"$(nproc)" ;;
    tsan) build_tsan ;;
    *) echo "usage: sanitize.sh build asan|tsan" >&2; exit 2 ;;
  esac
  exit 0
fi
case "$kind" in
  asan)
    configure_asan_tree
    dir="$asan_tree"
    cmake --build "$dir" -j"$(nproc)"
    export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
    export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
    # The quarter-hour GNSS drive is left to the native stage: its targets
    # are the estimator's, and the same code runs here in the GNSS loop, the
    # live GNSS run and the unit tests. So is the camera slip drive (160 s
    # here, a quarter of the stage's CPU): its checks are the filter's
    # response to a slip, and every line it runs, camera, odometry and
    # fusion, runs here in the camera's lockstep drives, the mapper's and
    # the live recording. So is the plain-wall drive (145 s here, the
    # stage's longest): its checks are the odometry's refusals of grey pairs
    # and the estimate's steadiness; the refusal runs here in the odometry's
    # unit tests (dark and flashed pairs), the drive's path (render, match,
    # fuse, record, replay) in the camera's lockstep drives. And the map's accuracy on
    # the obstacle course (every scoring; minutes here): it scores depth and map against the
    # world's truth; its renderer, matcher and map run here in the rendered
    # pairs' tests and the mapper's lockstep drive. And the navigator's
    # closed loop (30 s natively, minutes here) and its whole obstacle
    # course (65 s natively): its navigator runs here in
    # its own unit tests and in the daemon fuzzer, its drive in the
    # mapper's and the commanded base's lockstep drives. And the planner
    # against Boost on the mapped obstacle course: it maps the lap as the
    # accuracy test does (left to the native stage above), then compares
    # plans, which the random grids' comparison does here.
    (cd "$dir" && ctest --output-on-failure -j2 -L 'unit|integration' -LE reference \
      -E '^(integration_gnss_drive|integration_camera_slip|integration_plain_wall|SimMapAccuracy\..*|NavDrive\.FindsTheWallInItsOwnMapGoesRoundAndItsRecordingReplays|NavDrive\.TheObstacleCoursesTenGoalsEachReachedWithin30CmOfTheTruth|BoostGraphReference\.TheMappedObstacleCourseGivesBoostsCostsToo)$' "$@")
    ;;
  tsan)
    build_tsan
    export TSAN_OPTIONS="suppressions=$supp/tsan.supp:halt_on_error=1:second_deadlock_stack=1"
    "$dir/tests/rtfuse_unit_core" "$@"
    "$dir/tests/rtfuse_unit_runtime" "$@"
    # The daemon with every sensor: the loop, the IMU and camera threads,
    # the mapper, the publisher and the LCM thread at once. Under TSan a rendered frame
    # and its odometry take some 0.2 s, so config/sim.toml's camera runs at
    # 15 fps and its odometry restarts only after 2 s without a pair;
    # otherwise it would restart at every pair and never push a twist.
    # Its mapper takes a keyframe a second (one takes some 0.5 s here), and
    # the navigator's thread takes its grids (no goal: the drive is scripted).
    sed -e 's/^fps = 30$/fps = 15/' -e 's/^max_interval = 0.25 .*/max_interval = 2.0/' \
      -e 's/^keyframe_interval = 0.2 /keyframe_interval = 1.0 /' \
      "$root/config/sim.toml" >"$dir/sim_tsan.toml"
    printf '\n[navigation]\n' >>"$dir/sim_tsan.toml"
    ln -sfn "$root/config/calibration" "$dir/calibration"
    ln -sfn "$root/config/scenarios" "$dir/scenarios"
    echo "sanitize.sh: rtfused under ThreadSanitizer, 8 s on the simulated robot"
    "$dir/src/apps/rtfused" --config "$dir/sim_tsan.toml" --duration 8 --lcm-url memq:// --quiet | tee "$dir/rtfused.out"
    if ! grep -q "visual odometry.*motions [1-9]" "$dir/rtfused.out"; then
      echo "sanitize.sh: the visual odometry made no motion under TSan: its twists went unchecked" >&2
      exit 1
    fi
    if ! grep -q "device mapper.*inserted [1-9]" "$dir/rtfused.out"; then
      echo "sanitize.sh: the mapper mapped no keyframe under TSan: its threads went unchecked" >&2
      exit 1
    fi
    echo "sanitize.sh: rtfused under ThreadSanitizer: no finding"
    ;;
  *)
    echo "usage: sanitize.sh asan|tsan [ctest args (asan) | gtest args (tsan)...]" >&2
    exit 2
    ;;
esac
