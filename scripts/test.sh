#!/usr/bin/env bash
# Sets everything up (Debian packages, build) and runs the test suite three times:
#   1. Release build            (build/),       ctest (with the ROS node end to end through roscore)
#   2. AddressSanitizer + UBSan (build-asan/, clang),  ctest
#   3. ThreadSanitizer          (build-tsan/),  the tests of everything that runs threads of its
#      own: the runtime's background mode and its worker, the clocks, the push queues, the C API's runtime with
#      its own thread and pushes from three threads, the ROS node (its control and publishing threads,
#      against the Release build's simulator bridge through roscore). They run their TBB work in
#      one-thread arenas: Debian's TBB is not instrumented, so TSan cannot see TBB's own
#      synchronisation (its parallel loops would show as races).
#   4. Fuzzing                  (build-fuzz/),  every libFuzzer target (clang, ASan + UBSan +
#      LeakSanitizer) for DUET_FUZZ_SECONDS (default 20) seconds each, one per core at a time:
#      scripts/fuzz.sh.
# New build folders use Ninja; test files compile in unity batches (tests/CMakeLists.txt).
# Each test executable runs as DUET_TEST_SHARDS (default 4; test_runtime 3x) ctest tests (gtest sharding): a test
# executable's process start costs ~0.4 s of CPU in Release and ~0.9 s under ASan, which over
# 600 tests was ~13 minutes of a 2-core run (tests/CMakeLists.txt). A failing shard prints its
# whole output; rerun one test with e.g. build/tests/test_runtime --gtest_filter='SimExplore.*'.
# Usage: scripts/test.sh            all passes
#        DUET_SKIP_SANITIZERS=1 scripts/test.sh   only the Release pass
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="$(nproc 2>/dev/null || echo 2)"
shards="-DDUET_TEST_SHARDS=${DUET_TEST_SHARDS:-4}"

echo "== duet: Release build and tests"
# The sanitizer stages' compiler (clang 14) is installed in the background while the Release build
# compiles: its download and unpacking then cost the run no time of its own. Should that fail, the
# ASan stage's setup.sh installs it again (and stops with apt's error if it cannot).
sanitizer_pkgs="clang-14 libclang-rt-14-dev"
clang_install=""
DUET_SETUP_PACKAGES_ONLY=1 "$here/scripts/setup.sh"
if [ "${DUET_SKIP_SANITIZERS:-0}" != 1 ]; then
  mkdir -p "$here/build"
  DUET_EXTRA_PKGS="$sanitizer_pkgs" DUET_SETUP_PACKAGES_ONLY=1 "$here/scripts/setup.sh" > "$here/build/apt-clang.log" 2>&1 &
  clang_install=$!
fi
"$here/scripts/setup.sh" "$here/build" "$shards"
(cd "$here/build" && ctest --output-on-failure -j "$jobs" --timeout 900)
if [ -n "$clang_install" ] && ! wait "$clang_install"; then
  echo "test.sh: installing $sanitizer_pkgs in the background failed (build/apt-clang.log); the ASan stage tries again" >&2
fi

if [ "${DUET_SKIP_SANITIZERS:-0}" != 1 ]; then
  echo "== duet: AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
  # The ASan + UBSan build uses clang (as the fuzz build does): it compiles it ~40 % faster than gcc.
  DUET_EXTRA_PKGS="$sanitizer_pkgs" CC=clang-14 CXX=clang++-14 DUET_BUILD_TYPE=RelWithDebInfo \
    "$here/scripts/setup.sh" "$here/build-asan" "$shards" -DDUET_SANITIZE=ON -DDUET_BUILD_BENCH=OFF
  export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:strict_string_checks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  (cd "$here/build-asan" && ctest --output-on-failure -j "$jobs" --timeout 1800)

  echo "== duet: ThreadSanitizer build and the threaded tests"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$here/tests/tsan.supp"
  tsan_targets="test_threads test_capi_threads" tsan_labels='test_threads|test_capi_threads' tsan_args=()
  if [ -x "$here/build/ros/duet_sim_ros" ]; then  # the ROS node's own threads, against the Release bridge
    tsan_targets+=" duet_ros" tsan_labels+='|ros_node_threads' tsan_args=(-DDUET_ROS_SIM_BRIDGE="$here/build/ros/duet_sim_ros")
  fi
  # gcc here: with clang's TSan, the ROS node's boost::shared_ptr messages, released inside
  # Debian's uninstrumented libroscpp, show as a race (ros_node_threads; it passes with gcc's build).
  DUET_BUILD_TYPE=RelWithDebInfo DUET_BUILD_TARGETS="$tsan_targets" \
    "$here/scripts/setup.sh" "$here/build-tsan" "$shards" -DDUET_SANITIZE_THREAD=ON -DDUET_BUILD_BENCH=OFF "${tsan_args[@]}"
  (cd "$here/build-tsan" && ctest --output-on-failure -j "$jobs" --timeout 1800 -L "^($tsan_labels)\$")

  echo "== duet: fuzzing, ${DUET_FUZZ_SECONDS:-20} s per target"
  FUZZ_SEED=1 FUZZ_BUILD="$here/build-fuzz" "$here/scripts/fuzz.sh" "${DUET_FUZZ_SECONDS:-20}"
fi
