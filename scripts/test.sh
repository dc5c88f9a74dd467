#!/usr/bin/env bash
# The test command: set up, build with -Werror, run every Check suite and end-to-end test
# through CTest (this includes the fuzz smoke run, tests/fuzz/smoke.sh, and valgrind memcheck
# on a short record + replay, tests/memcheck.sh); then build the whole project again in its own
# folder with AddressSanitizer + UndefinedBehaviorSanitizer and run the same suite there.
# SANITIZE=0 skips the sanitizer pass. Extra arguments go to both ctest runs.
# Both passes run two tests at a time (TEST_JOBS, default 2: CI's two cores; most tests leave a
# core idle in llvmpipe's serial vertex and binning work and in process start). The tests that
# time something or start daemons are RUN_SERIAL in tests/CMakeLists.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
BUILD_DIR=$BUILD_DIR scripts/setup.sh -DISPM_WERROR=ON
# setup.sh installed every dependency: a test that would skip for a missing one fails instead.
export ISPM_REQUIRE_DEPS=1
JOBS=${TEST_JOBS:-2}
(cd "$BUILD_DIR" && ctest --output-on-failure --timeout 900 -j"$JOBS" "$@")

if [ "${SANITIZE:-1}" != 0 ]; then
  SAN_DIR=${SANITIZE_BUILD_DIR:-$BUILD_DIR-sanitize}
  echo "test: the suite again under ASan + UBSan ($SAN_DIR)"
  cmake -S . -B "$SAN_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISPM_WERROR=ON -DISPM_SANITIZE=ON > /dev/null
  cmake --build "$SAN_DIR" -j"$(nproc)"
  # Suppressions name third-party libraries only; why each: tests/sanitizers/README.md.
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:malloc_context_size=10}
  export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  # Two kills instead of three in the crash test: the code paths are the same, and ASan's
  # slowdown of the renderer keeps the whole command within the CI budget.
  # Not repeated here: fuzz_smoke (its fuzzers are already built with ASan + libFuzzer),
  # memcheck (valgrind cannot run ASan binaries), e2e_viewer (a GUI timing test of the same
  # code test_viewer covers; under ASan its screenshots race the slower first frame),
  # e2e_stability (25 stress sequences through the same record/replay code e2e_regression and
  # the method e2e tests run here; 145 s under ASan, which would take the command past 20 min),
  # e2e_slurm (a second Slurm cluster for the same record and merge code that e2e_cli runs here),
  # e2e_faults (it preloads its fault library, and ASan's runtime must come first in the list of
  # initial libraries; e2e_hostile runs the same failing writes here: full disk, interrupted swaps).
  (cd "$SAN_DIR" && CRASH_KILLS=2 ctest --output-on-failure --timeout 900 -j"$JOBS" -E 'fuzz_smoke|memcheck|e2e_viewer|e2e_stability|e2e_slurm|e2e_faults' "$@")
fi
