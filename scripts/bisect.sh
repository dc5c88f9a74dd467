#!/usr/bin/env bash
# bisect.sh GOOD BAD SEQUENCE [--golden DIR] — names the first commit between GOOD and BAD at
# which `ispm check SEQUENCE` turns bad, with git bisect run.
#
# It works in a scratch worktree (your checkout is left alone) and builds each commit it tests
# in one scratch build folder (incremental between steps; only the ispm target). The golden is
# copied first from the current checkout (DIR, default golden/<sequence name>) so that every
# commit is judged against the same golden. SEQUENCE is a path inside the repository: each
# commit's own version of it (and of its scene) is recorded. A commit that does not build is
# skipped (exit 125), as is one that cannot be judged.
#
# ISPM_BISECT_BIN=PATH skips the builds and uses that ispm for every commit: for a regression in
# the inputs (a scene, a sequence's settings) rather than in the code.
# ISPM_BISECT_WORK=DIR keeps the scratch worktree and build there (default: a temporary folder,
# removed at the end). ISPM_BISECT_JOBS: build parallelism (default 2).
#
# exit: 0 the first bad commit was found (printed as "first bad commit: SHA subject");
#       1 bisection failed (no bad commit found, or every commit skipped); 2 bad arguments
set -u
usage() { echo "usage: scripts/bisect.sh GOOD BAD SEQUENCE [--golden DIR]" >&2; exit 2; }

if [ "${1:-}" = "--step" ]; then
  # One bisection step, run by git bisect inside the scratch worktree: build, then check.
  shift; WT=$1; BUILD=$2; SEQ=$3; GOLDEN=$4
  if [ -n "${ISPM_BISECT_BIN:-}" ]; then
    ISPM=$ISPM_BISECT_BIN
  else
    { cmake -S "$WT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$BUILD.log" 2>&1 &&
      nice cmake --build "$BUILD" --target ispm -j "${ISPM_BISECT_JOBS:-2}" >> "$BUILD.log" 2>&1; } || {
      echo "bisect: $(git -C "$WT" rev-parse --short HEAD) does not build: skipped (see $BUILD.log)"; exit 125; }
    ISPM=$BUILD/cli/ispm
  fi
  cd "$WT" || exit 125
  "$ISPM" check "$SEQ" --golden "$GOLDEN" --quiet
  rc=$?
  case $rc in 0|1|125) exit $rc ;; *) exit 125 ;; esac
fi

[ $# -ge 3 ] || usage
GOOD=$1; BAD=$2; SEQ=$3; shift 3
GOLDEN=""
while [ $# -gt 0 ]; do
  case $1 in
    --golden) [ $# -ge 2 ] || usage; GOLDEN=$2; shift 2 ;;
    *) usage ;;
  esac
done
TOP=$(git rev-parse --show-toplevel 2>/dev/null) || { echo "bisect: not inside a git repository" >&2; exit 2; }
for c in "$GOOD" "$BAD"; do
  git -C "$TOP" rev-parse --verify -q "$c^{commit}" > /dev/null || { echo "bisect: $c: not a commit" >&2; exit 2; }
done
if [ -z "$GOLDEN" ]; then
  name=$(sed -n 's/^ *"name": *"\([^"]*\)".*/\1/p' "$TOP/$SEQ" | head -n 1)
  [ -n "$name" ] || { echo "bisect: $SEQ: no \"name\" to find its golden; give --golden DIR" >&2; exit 2; }
  GOLDEN=$TOP/golden/$name
fi
[ -f "$GOLDEN/manifest.json" ] || { echo "bisect: $GOLDEN: no golden there (no manifest.json)" >&2; exit 2; }

WORK=${ISPM_BISECT_WORK:-$(mktemp -d "${TMPDIR:-/tmp}/ispm-bisect-XXXXXX")}
mkdir -p "$WORK" && WORK=$(cd "$WORK" && pwd) || exit 2
GOLDEN=$(cd "$GOLDEN" && pwd) || exit 2
cleanup() {
  git -C "$WORK/wt" bisect reset > /dev/null 2>&1
  git -C "$TOP" worktree remove --force "$WORK/wt" > /dev/null 2>&1
  [ -n "${ISPM_BISECT_WORK:-}" ] || rm -rf "$WORK"
}
trap cleanup EXIT
if grep -q '"format_version": *2' "$GOLDEN/manifest.json"; then
  # A golden of stored objects: the commits under test may read only frame files, so it is
  # unpacked with this tree's ispm (ISPM, default build/cli/ispm) into frame files first.
  ISPM_NOW=${ISPM:-$TOP/build/cli/ispm}
  [ -x "$ISPM_NOW" ] || { echo "bisect: $GOLDEN stores objects: build $ISPM_NOW (or set ISPM) to unpack it" >&2; exit 2; }
  "$ISPM_NOW" golden unpack "$GOLDEN" "$WORK/golden" > /dev/null || exit 2
else
  cp -r "$GOLDEN" "$WORK/golden" || exit 2
fi
git -C "$TOP" worktree add --detach "$WORK/wt" "$BAD" > /dev/null 2>&1 || { echo "bisect: cannot add a worktree in $WORK" >&2; exit 2; }
SELF=$(cd "$(dirname "$0")" && pwd)/$(basename "$0")
cd "$WORK/wt" || exit 2
git bisect start "$BAD" "$GOOD" > /dev/null || exit 2
git bisect run bash "$SELF" --step "$WORK/wt" "$WORK/build" "$SEQ" "$WORK/golden" > "$WORK/bisect.log" 2>&1
first=$(sed -n 's/^\([0-9a-f]\{40\}\) is the first bad commit$/\1/p' "$WORK/bisect.log" | head -n 1)
if [ -z "$first" ]; then
  cat "$WORK/bisect.log"
  echo "bisect: no first bad commit found"
  exit 1
fi
echo "first bad commit: $(git log -1 --format='%H %s' "$first")"
exit 0
