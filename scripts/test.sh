#!/usr/bin/env bash
# The one test command (README, .ci/run): installs what is missing, builds, runs every test.
#   1. release build (RelWithDebInfo): the whole suite
#   2. AddressSanitizer + UndefinedBehaviorSanitizer build (Debug at -O1): the whole suite
#      except the long-running integration sequences (label 'slow')
#   3. ThreadSanitizer build: the frame ring and the runtime threads (label 'threads')
#   4. arm64: cross build and the smoke set under qemu-user (scripts/test_arm64.sh --smoke,
#      docs/platforms.md)
# Set EMF_TEST_STAGES="release" (or "release asan tsan arm64", the default) to choose.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh

stages="${EMF_TEST_STAGES:-release asan tsan arm64}"
jobs="${EMF_JOBS:-$(nproc)}"
status=0
for stage in $stages; do
  echo "=== emf tests: $stage ==="
  case "$stage" in
    release)
      bash scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
      (cd build && ctest --output-on-failure -j "$jobs") || status=1
      ;;
    asan)
      # -O1, as AddressSanitizer's documentation advises: unoptimised, the CPU-side renderer
      # and reference code run many times slower than in the release build, and tests near their
      # time limit on a slow 2-core machine.
      bash scripts/build.sh build-asan -DCMAKE_BUILD_TYPE=Debug -DEMF_SANITIZE=address,undefined \
        -DEMF_BUILD_BENCH=OFF -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" -DCMAKE_C_FLAGS_DEBUG="-g -O1"
      # PoCL's own (unsanitized) runtime keeps allocations until exit: leaks are not ours.
      (cd build-asan && ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 \
         UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
         ctest --output-on-failure -j "$jobs" -LE 'slow|install') || status=1
      ;;
    tsan)
      EMF_BUILD_TARGET=emf_threads_tests bash scripts/build.sh build-tsan \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEMF_SANITIZE=thread -DEMF_BUILD_BENCH=OFF
      (cd build-tsan && TSAN_OPTIONS=halt_on_error=1 \
         ctest --output-on-failure -j "$jobs" -L threads --no-tests=ignore) || status=1
      ;;
    arm64)
      bash scripts/test_arm64.sh --smoke || status=1
      ;;
    *)
      echo "unknown stage '$stage' (release, asan, tsan, arm64)" >&2
      exit 2
      ;;
  esac
done
exit $status
