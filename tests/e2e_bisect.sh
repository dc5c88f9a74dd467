#!/usr/bin/env bash
# scripts/bisect.sh names the commit that injected a regression: a throwaway git history of a
# small scene (5 commits; the third changes a setting of the sequence, the others touch a
# README), a golden recorded from the first, and bisect run over it with the already-built ispm
# (ISPM_BISECT_BIN: a full build per step would take minutes on CI's two cores; the build path
# of bisect.sh is the same script with cmake in front of the check).
# usage: e2e_bisect.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$(cd "$(dirname "$1")" && pwd)/$(basename "$1"); SRC=$(cd "$2" && pwd); WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
command -v git > /dev/null || { [ "${ISPM_REQUIRE_DEPS:-0}" = 1 ] && fail "git missing"; echo "SKIP: git not installed"; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK/repo/s"
WORK=$(cd "$WORK" && pwd)
cd "$WORK/repo" || exit 1
git init -q . || fail "git init"
commit() { git add -A && git -c user.name=e2e -c user.email=e2e@example.invalid commit -q -m "$1" || fail "commit $1"; }
cp "$SRC/scenes/cornell-box/cornell-box.gltf" s/
seq() {
  printf '{"name": "bisect-small", "scene": "cornell-box.gltf", "frames": 1, "fps": 8, "resolution": [32, 32],
  "camera": {"node": "Camera"}, "settings": {"shadow_map_size": 64, "photon_count": 1024, "kernel_radius": %s,
  "threads": 2}, "capture": ["final.display", "indirect.radiance"]}\n' "$1" > s/seq.json
}
seq 0.15; echo one > README; commit "good: the scene"
echo two >> README; commit "docs"
seq 0.3; commit "tune the kernel radius"       # the injected regression
echo three >> README; commit "more docs"
echo four >> README; commit "even more docs"
GOOD=$(git rev-list --max-parents=0 HEAD)
INJECTED=$(git rev-parse HEAD~2)

git checkout -q "$GOOD" || fail "checkout"
"$ISPM" record s/seq.json -o "$WORK/run" --quiet > /dev/null || fail "record the golden"
"$ISPM" bless "$WORK/run" "$WORK/golden" > /dev/null || fail "bless the golden"
git checkout -q - || fail "checkout back"

ISPM_BISECT_BIN=$ISPM bash "$SRC/scripts/bisect.sh" "$GOOD" HEAD s/seq.json --golden "$WORK/golden" > "$WORK/bisect.txt" 2>&1
rc=$?
cat "$WORK/bisect.txt"
[ $rc -eq 0 ] || fail "bisect.sh exited $rc"
grep -q "^first bad commit: $INJECTED tune the kernel radius" "$WORK/bisect.txt" || fail "bisect did not name $INJECTED"
[ -z "$(git worktree list | sed -n 2p)" ] || fail "bisect left a worktree behind"
[ "$(git status --porcelain)" = "" ] || fail "bisect touched the checkout"
# bad arguments
bash "$SRC/scripts/bisect.sh" "$GOOD" nosuchcommit s/seq.json --golden "$WORK/golden" > /dev/null 2>&1
[ $? -eq 2 ] || fail "bisect.sh with a bad commit must exit 2"
echo "e2e_bisect: ok"
