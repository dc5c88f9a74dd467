#!/usr/bin/env bash
# End-to-end EGL backend (issue 21): the CI sequence recorded through OSMesa and through Mesa's
# EGL (surfaceless, llvmpipe, same pinned settings) gives the same digest for every buffer of
# every frame, and the EGL run replays bit-exact against the OSMesa golden (same renderer).
# --gl's errors: a bad backend, --gl-device without egl, a device the machine lacks, and EGL
# with no implementation (glvnd pointed at no vendor) are one-line errors with their exit
# codes. Goldens per renderer: the same run claiming another GL renderer is reported as
# "different renderer" and compared under the cross-renderer tolerances (one changed pixel
# that fails the golden's own tolerances passes the looser cross-renderer ones).
# usage: e2e_egl.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
MUTATE=$(dirname "$ISPM")/../tests/ispm_test_mutate
SEQ=$SRC/scenes/cornell-box/cornell-box-ci.json
GOLDEN=$SRC/golden/cornell-box-ci
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"

# One line on stderr, exit code $1, message matching $2; the rest is the command.
one_line() {
  local want=$1 pattern=$2; shift 2
  "$@" > /dev/null 2> "$WORK/err"; local rc=$?
  [ $rc -eq "$want" ] || fail "$* exited $rc, want $want: $(cat "$WORK/err")"
  [ "$(wc -l < "$WORK/err")" -eq 1 ] || fail "$*: not one line: $(cat "$WORK/err")"
  grep -q -- "$pattern" "$WORK/err" || fail "$*: message '$(cat "$WORK/err")' lacks '$pattern'"
  echo "ok ($rc): $(cat "$WORK/err")"
}
one_line 2 "'vulkan' is not a GL backend (osmesa, egl)" "$ISPM" record "$SEQ" -o "$WORK/x" --gl vulkan
one_line 2 "gl-device needs --gl egl" "$ISPM" record "$SEQ" -o "$WORK/x" --gl-device 0
one_line 2 "gl-device: 'x'" "$ISPM" record "$SEQ" -o "$WORK/x" --gl egl --gl-device x
one_line 2 "gl-device 77: this machine has" "$ISPM" record "$SEQ" -o "$WORK/x" --gl egl --gl-device 77 --quiet
one_line 1 "EGL: unavailable" env __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent/egl.json \
  "$ISPM" record "$SEQ" -o "$WORK/x" --gl egl --quiet
[ ! -e "$WORK/x/manifest.json" ] || fail "a failed record wrote a manifest"

"$ISPM" record "$SEQ" -o "$WORK/osmesa" --quiet || fail "record through OSMesa exited $?"
"$ISPM" record "$SEQ" -o "$WORK/egl" --gl egl --quiet || fail "record through EGL exited $?"
python3 - "$WORK/osmesa/manifest.json" "$WORK/egl/manifest.json" <<'PY' || fail "digests differ"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
assert a["gl"]["backend"] == "osmesa" and b["gl"]["backend"] == "egl", (a["gl"], b["gl"])
assert b["gl"]["device"] == "surfaceless", b["gl"]
assert a["gl"]["renderer"] == b["gl"]["renderer"], (a["gl"], b["gl"])
da = [(f["index"], x["name"], x["digest"]) for f in a["frames"] for x in f["buffers"]]
db = [(f["index"], x["name"], x["digest"]) for f in b["frames"] for x in f["buffers"]]
assert len(da) > 100, len(da)
diff = [(p, q) for p, q in zip(da, db) if p != q]
assert len(da) == len(db) and not diff, diff[:3]
print("OSMesa and EGL: %d buffer digests equal" % len(da))
PY
"$ISPM" replay "$WORK/egl" --golden "$GOLDEN" --quiet > "$WORK/replay.out"; rc=$?
cat "$WORK/replay.out"
[ $rc -eq 0 ] || fail "EGL run against the OSMesa golden exited $rc"
grep -q "0 within tolerance, [0-9]* bit-exact" "$WORK/replay.out" || fail "EGL run not bit-exact against the golden"
grep -q "different renderer" "$WORK/egl/replay/report.txt" && fail "same renderer reported as different"

# One pixel changed by 0.01: fails the golden's own tolerances...
cp -r "$WORK/egl" "$WORK/pixel"
"$MUTATE" "$WORK/pixel" 1 direct.radiance 80 70 R add 0.01 || fail "mutate"
"$ISPM" replay "$WORK/pixel" --golden "$GOLDEN" --quiet > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "a changed pixel, same renderer: replay exited $rc, want 2"
# ...and, from another renderer, is compared under the cross-renderer set instead.
python3 - "$WORK/pixel/manifest.json" <<'PY' || fail "cannot edit the manifest"
import json, sys
m = json.load(open(sys.argv[1]))
m["gl"]["renderer"] = "NVIDIA Test GPU/PCIe/SSE2"
json.dump(m, open(sys.argv[1], "w"), indent=1)
PY
"$ISPM" replay "$WORK/pixel" --golden "$GOLDEN" > "$WORK/cross.out"; rc=$?
cat "$WORK/cross.out" | head -6
[ $rc -le 1 ] || fail "a changed pixel, other renderer: replay exited $rc, want 0 or 1 (cross-renderer tolerances)"
grep -q 'different renderer: run "NVIDIA Test GPU/PCIe/SSE2", golden "llvmpipe' "$WORK/cross.out" \
  || fail "summary does not say different renderer"
grep -q "tolerances built-in cross-renderer defaults" "$WORK/cross.out" || fail "summary does not name the cross-renderer set"
python3 - "$WORK/pixel/replay/report.json" <<'PY' || fail "report.json lacks the renderer block"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["renderer"]["different"] is True and r["renderer"]["run"].startswith("NVIDIA"), r.get("renderer")
assert r["tolerances"] == "built-in cross-renderer defaults", r["tolerances"]
PY
grep -q "different renderer" "$WORK/pixel/replay/report.html" || fail "report.html does not say different renderer"
echo "PASS"
