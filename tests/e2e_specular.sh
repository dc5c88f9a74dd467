#!/usr/bin/env bash
# Specular eye paths (issue 14): the glass sphere of cornell-glass, recorded at 64×64, is not
# black and matches the reference renderer within the issue's goal (sphere pixels: mean within
# 10%, 8×8-block p90 relative error ≤ 25%, no black pixel where the reference shows light);
# with "specular": "envmap" it is not black and its mean within 20%; with "specular": "off" it
# is black (so the comparison can fail); specular.* are bit-identical
# for 1 and 3 threads; a bad "specular" value is one error line and exit 2; an emitter is seen
# (gbuffer.emission, composite, reference).
# usage: e2e_specular.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$(cd "$2" && pwd); WORK=$3
CMP=$(dirname "$ISPM")/../tests/ispm_test_specular
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
SCENE=$SRC/scenes/cornell-box/cornell-glass.gltf
seq() { # NAME EXTRA_SETTINGS
  cat > "$WORK/$1.json" <<JSON
{"name": "$1", "scene": "$SCENE", "frames": 1, "fps": 8, "resolution": [64, 64], "camera": {"node": "Camera"},
 "settings": {"shadow_map_size": 256, "photon_count": 16384, "kernel_radius": 0.15$2}, "capture": ["*"]}
JSON
}
seq traced ""
seq off ', "specular": "off"'
seq envmap ', "specular": "envmap"'
seq bad ', "specular": "mirror"'

"$ISPM" record "$WORK/traced.json" -o "$WORK/t1" --threads 1 --quiet > /dev/null || fail "record traced exited $?"
"$ISPM" record "$WORK/traced.json" -o "$WORK/t3" --threads 3 --quiet > /dev/null || fail "record traced --threads 3 exited $?"
"$ISPM" record "$WORK/off.json" -o "$WORK/off" --quiet > /dev/null || fail "record off exited $?"
"$ISPM" record "$WORK/envmap.json" -o "$WORK/envmap" --quiet > /dev/null || fail "record envmap exited $?"
"$ISPM" reference "$WORK/traced.json" -o "$WORK/ref" --spp 128 --quiet > /dev/null || fail "reference exited $?"

python3 - "$WORK" <<'PY' || fail "manifests"
import json, sys
w = sys.argv[1]
def bufs(run):
    m = json.load(open(f"{w}/{run}/manifest.json"))
    return m, {b["name"]: b["digest"] for b in m["frames"][0]["buffers"]}
m1, b1 = bufs("t1")
m3, b3 = bufs("t3")
mo, bo = bufs("off")
for n in ("specular.radiance", "specular.depth", "specular.throughput", "composite.radiance"):
    assert n in b1, n
    assert b1[n] == b3[n], f"{n} differs between 1 and 3 threads"
assert not any(n.startswith("specular.") for n in bo), "specular.* announced with specular off"
assert m1["settings"]["specular"] == "traced" and m1["settings"]["specular_depth"] == 4, m1["settings"]
assert mo["settings"]["specular"] == "off", mo["settings"]
assert any(p["name"] == "specular" for p in m1["frames"][0]["passes"]), "no specular pass time"
PY

read_cmp() { "$CMP" "$@" || fail "ispm_test_specular $* exited $?"; }
line=$(read_cmp "$WORK/t1" "$WORK/ref")
echo "traced: $line"
set -- $line
[ "$2" -gt 50 ] || fail "only $2 glass pixels"
python3 -c "import sys; r, p = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if 0.9 <= r <= 1.1 and p <= 0.25 else 1)" \
  "$4" "$6" || fail "glass pixels: mean ratio $4 (goal 0.9..1.1), block p90 $6 (goal <= 0.25)"
[ "$8" -eq 0 ] || fail "$8 glass pixels black where the reference shows light"
# The envmap approximation (no second refraction, seen from the centre): not black, mean within
# 20% (measured 0.98 at 256², its block p90 0.52 is the approximation's, README).
line=$(read_cmp "$WORK/envmap" "$WORK/ref")
echo "envmap: $line"
set -- $line
python3 -c "import sys; r = float(sys.argv[1]); sys.exit(0 if 0.8 <= r <= 1.2 else 1)" "$4" || fail "envmap mean ratio $4"
[ "$8" -eq 0 ] || fail "envmap: $8 glass pixels black where the reference shows light"
line=$(read_cmp "$WORK/off" "$WORK/ref")
echo "off: $line"
set -- $line
[ "$8" -gt 0 ] || fail "with specular off the sphere should be black: $line"

"$ISPM" record "$WORK/bad.json" -o "$WORK/bad" --quiet 2> "$WORK/err.txt" > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "bad specular value: exit $rc, want 2"
[ "$(wc -l < "$WORK/err.txt")" -eq 1 ] && grep -q "settings.specular" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "bad specular: want one line naming settings.specular"; }
# Emission (emissiveFactor × KHR_materials_emissive_strength): the tall box glows (40, 20, 10)
# W/m²/sr in gbuffer.emission, in the composite and in the reference renderer's image.
python3 - "$SCENE" "$WORK/emissive.gltf" <<'PY' || fail "making the emissive scene"
import json, sys
g = json.load(open(sys.argv[1]))
m = next(m for m in g["materials"] if m["name"] == "tallBox")
m["emissiveFactor"] = [1.0, 0.5, 0.25]
m.setdefault("extensions", {})["KHR_materials_emissive_strength"] = {"emissiveStrength": 40.0}
g["extensionsUsed"].append("KHR_materials_emissive_strength")
json.dump(g, open(sys.argv[2], "w"))
PY
SCENE=$WORK/emissive.gltf seq emissive ""
"$ISPM" record "$WORK/emissive.json" -o "$WORK/emis" --quiet > /dev/null || fail "record emissive exited $?"
"$ISPM" reference "$WORK/emissive.json" -o "$WORK/emisref" --spp 2 --photons 1024 --quiet > /dev/null || fail "reference emissive exited $?"
maxof() { # RUN PART: the part's per-channel maxima
  oiiotool "$1/frames/000000.exr" --subimage "$2" --printstats 2>/dev/null | sed -n 's/.*Stats Max: *//p'
}
[ "$(maxof "$WORK/emis" gbuffer.emission)" = "40.000000 20.000000 10.000000 (float)" ] ||
  fail "gbuffer.emission max: $(maxof "$WORK/emis" gbuffer.emission)"
for p in "emis composite.radiance" "emisref reference.direct"; do
  set -- $p
  python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 40.0 else 1)" $(maxof "$WORK/$1" "$2") ||
    fail "$2 does not show the emitter: max $(maxof "$WORK/$1" "$2")"
done
echo "PASS"
