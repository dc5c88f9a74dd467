#!/usr/bin/env bash
# Multi-image photon tracing end to end (issue 16, 004 §4-5): record the CI sequence with
# "photon_trace": "multi-image" (2 maps, the short box moving: the maps are placed again every
# frame); replay it against its golden (bit-exact) when the golden exists; the same recording
# with 1 thread is bit-identical; a recording resumed after its last frames were lost ends
# bit-identical; every frame's manifest names 2 centres and accounts for every ray (resolved +
# fallback + dropped), the cube G-buffers are captured with their 6 material channels; with
# "multi_image_miss": "drop" the misses are dropped, not traced; a bad setting is refused
# (exit 2, one line naming the file).
# usage: e2e_multiimage.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
SEQ=$SRC/scenes/cornell-box/cornell-box-multiimage-ci.json
GOLDEN=$SRC/golden/cornell-box-multiimage-ci
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
bitexact() { # bitexact RUN GOLDEN LABEL
  "$ISPM" replay "$1" --golden "$2" --report "$WORK/replay-$3" > "$WORK/$3.out"; rc=$?
  [ $rc -eq 0 ] || { cat "$WORK/$3.out"; fail "$3: replay exited $rc"; }
  grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/$3.out" || { cat "$WORK/$3.out"; fail "$3: not bit-exact"; }
}
# variant NAME FRAMES SED-EXPR: the CI sequence with FRAMES frames and one more edit.
variant() {
  sed -e "s/\"frames\": 8/\"frames\": $2/" -e "$3" \
      -e "s#\"cornell-box.gltf\"#\"$SRC/scenes/cornell-box/cornell-box.gltf\"#" "$SEQ" > "$WORK/$1.json"
}

"$ISPM" record "$SEQ" -o "$WORK/run" --quiet > /dev/null || fail "record exited $?"
if [ -d "$GOLDEN" ]; then
  bitexact "$WORK/run" "$GOLDEN" golden
fi

python3 - "$WORK/run/manifest.json" <<'PY' || fail "manifest check"
import json, sys
m = json.load(open(sys.argv[1]))
s = m["settings"]
assert s["photon_trace"] == "multi-image" and s["multi_image_maps"] == 2 and s["multi_image_size"] == 32, s
assert s["multi_image_miss"] == "embree", s
for f in m["frames"]:
    t = f["photon_trace"]
    assert len(t["centres"]) == 2 and all(len(c) == 3 for c in t["centres"]), t
    assert t["rays"] > 0 and t["rays"] == t["resolved"] + t["fallback"] + t["dropped"], t
    assert t["dropped"] == 0 and t["fallback"] > 0 and t["resolved"] > t["fallback"], t
    assert sum(t["types"]) == 2 * t["rays"], t
    assert "multiimage" in [p["name"] for p in f["passes"]]
    names = {b["name"]: b for b in f["buffers"]}
    for k in range(2):
        for face in range(6):
            for part in ("position", "normal", "material"):
                b = names["multiimage.map%d.face%d.%s" % (k, face, part)]
                assert b["width"] == 32 and b["height"] == 32, b
    assert sorted(names["multiimage.map1.face5.material"]["channels"]) == \
        ["draw", "id", "ior", "metallic", "roughness", "transmission"], names["multiimage.map1.face5.material"]
print("manifest ok")
PY

# One thread: bit-identical.
"$ISPM" record "$SEQ" -o "$WORK/t1" --threads 1 --quiet > /dev/null || fail "record --threads 1 exited $?"
bitexact "$WORK/t1" "$WORK/run" threads

# Resumed after the last three frames were lost.
cp -r "$WORK/run" "$WORK/resumed"
rm -f "$WORK/resumed/manifest.json" "$WORK"/resumed/frames/00000{5,6,7}.{exr,json}
"$ISPM" record "$SEQ" -o "$WORK/resumed" --resume --quiet > /dev/null || fail "record --resume exited $?"
bitexact "$WORK/resumed" "$WORK/run" resume

# Misses dropped: counted, none traced by Embree, and fewer photons stored.
variant drop 1 's/"multi_image_size": 32/"multi_image_size": 32, "multi_image_miss": "drop"/'
"$ISPM" record "$WORK/drop.json" -o "$WORK/drop" --quiet > /dev/null || fail "drop: record exited $?"
python3 - "$WORK/drop/manifest.json" "$WORK/run/manifest.json" <<'PY' || fail "drop check"
import json, sys
d = json.load(open(sys.argv[1]))["frames"][0]
r = json.load(open(sys.argv[2]))["frames"][0]
t = d["photon_trace"]
assert t["fallback"] == 0 and t["dropped"] > 0 and t["rays"] == t["resolved"] + t["dropped"], t
assert d["photons"]["emitted"] == r["photons"]["emitted"]
assert sum(d["photons"]["stored"]) < sum(r["photons"]["stored"]), (d["photons"], r["photons"])
print("drop ok")
PY

# Bad input: exit 2, one line naming the file.
variant bad 1 's/"multi-image"/"multi-imge"/'
"$ISPM" record "$WORK/bad.json" -o "$WORK/bad" --quiet > /dev/null 2> "$WORK/bad.err"; rc=$?
[ $rc -eq 2 ] || fail "bad photon_trace: exit $rc, want 2"
[ "$(wc -l < "$WORK/bad.err")" -eq 1 ] && grep -q "bad.json.*photon_trace" "$WORK/bad.err" || { cat "$WORK/bad.err"; fail "bad photon_trace: message"; }
variant bad2 1 's/"multi_image_maps": 2/"multi_image_maps": 9/'
"$ISPM" record "$WORK/bad2.json" -o "$WORK/bad2" --quiet > /dev/null 2> "$WORK/bad2.err"; rc=$?
[ $rc -eq 2 ] || fail "multi_image_maps 9: exit $rc, want 2"
grep -q "multi_image_maps" "$WORK/bad2.err" || { cat "$WORK/bad2.err"; fail "multi_image_maps 9: message"; }
echo "e2e_multiimage: ok"
