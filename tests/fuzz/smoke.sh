#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan + coverage) in their own build folder
# (without -Werror: clang warns differently from gcc, and the gcc -Werror build is the gate)
# and runs each for FUZZ_SECONDS (default 20) from the seed corpus below. Any crash, sanitizer
# report, leak, timeout or contract violation fails the run and leaves the input in WORK/.
# CTest runs it as `fuzz_smoke`; docs/fuzzing.md explains long runs (FUZZ_SECONDS=600 ...).
# usage: smoke.sh SOURCE_DIR WORK_DIR [TARGET...]
set -euo pipefail
SRC=$(cd "$1" && pwd); WORK=$2; shift 2
SECONDS_EACH=${FUZZ_SECONDS:-20}
# A fixed seed makes the CI smoke explore the same inputs on every run of one commit (a
# crash it finds is found again, and a commit that passed does not fail later by luck);
# FUZZ_SEED=0 lets libFuzzer pick one, for long runs.
SEED=${FUZZ_SEED:-1}
BUILD=${FUZZ_BUILD_DIR:-$WORK/build}
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(fuzz_gltf fuzz_sequence fuzz_run_reader)
command -v clang > /dev/null || { echo "fuzz smoke: clang is not installed (scripts/setup.sh installs it)"; exit 1; }
mkdir -p "$WORK"

cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DISPM_FUZZ=ON -DISPM_SANITIZE=ON -DISPM_WERROR=OFF > "$WORK/configure.log" \
  || { cat "$WORK/configure.log"; exit 1; }
cmake --build "$BUILD" -j"$(nproc)" --target "${TARGETS[@]}" > "$WORK/build.log" 2>&1 \
  || { tail -50 "$WORK/build.log"; exit 1; }

# Seeds: every glTF and sequence the project has (valid and malformed), the golden's
# tolerances, and a manifest + frame the run-reader target writes for its own fixture. The
# first byte of a run-reader input picks the reader (0 manifest, 1 tolerances, 2 EXR).
SEEDS=$WORK/seeds
rm -rf "$SEEDS"; mkdir -p "$SEEDS"/{fuzz_gltf,fuzz_sequence,fuzz_run_reader}
cp "$SRC"/tests/data/gltf/*.gltf "$SRC"/tests/data/gltf/*.glb "$SRC"/tests/data/scenes/*.gltf \
   "$SRC"/scenes/*/*.gltf "$SEEDS/fuzz_gltf/"
cp "$SRC"/scenes/*/*.json "$SEEDS/fuzz_sequence/"
for t in "$SRC"/golden/*/tolerances.json; do
  { printf '\001'; cat "$t"; } > "$SEEDS/fuzz_run_reader/tolerances-$(basename "$(dirname "$t")")"
done
FUZZ_RUN_READER_SEED="$SEEDS/fuzz_run_reader" "$BUILD/tests/fuzz/fuzz_run_reader" -runs=0 > /dev/null 2>&1

# Third-party code only (why: tests/sanitizers/README.md).
# A small quarantine: OpenEXR allocates (and frees) buffers as large as a mutated header asks.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=1:quarantine_size_mb=32}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$SRC/tests/sanitizers/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for t in "${TARGETS[@]}"; do
  corpus=$WORK/corpus/$t
  mkdir -p "$corpus" "$WORK/artifacts/$t"
  dict=()
  [ -f "$SRC/tests/fuzz/$t.dict" ] && dict=(-dict="$SRC/tests/fuzz/$t.dict")
  echo "fuzz smoke: $t for ${SECONDS_EACH}s (seed $SEED)"
  if ! "$BUILD/tests/fuzz/$t" "$corpus" "$SEEDS/$t" "${dict[@]}" -max_total_time="$SECONDS_EACH" -seed="$SEED" \
       -timeout=20 -rss_limit_mb=2560 -max_len=65536 -print_final_stats=1 \
       -artifact_prefix="$WORK/artifacts/$t/" > "$WORK/$t.log" 2>&1; then
    tail -60 "$WORK/$t.log"
    echo "fuzz smoke: $t FAILED; reproduce with: $BUILD/tests/fuzz/$t $WORK/artifacts/$t/<crash file>"
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$WORK/$t.log" | tr '\n' ' '; echo
  fi
done
[ $status -eq 0 ] && echo "fuzz smoke: ok"
exit $status
