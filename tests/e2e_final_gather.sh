#!/usr/bin/env bash
# The final gather's settings end to end (docs/final-gather.md): a 48² Cornell box recorded with
# "preset": "interactive" writes a manifest that records the preset and every expanded setting
# (and a sequence key given beside the preset wins); the record replays clean and a second
# record is bit-identical to it; a record resumed after its last frame was lost rebuilds the
# reuse history and ends bit-identical; with surface seeds the near-plane walk's reprojected
# indirect flicker is below that of pixel seeds; a bad preset is refused with one line naming
# the file (exit 2); the bench's final-gather configs are valid.
# usage: e2e_final_gather.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
seq_with() { # seq_with OUT FRAMES SETTINGS (JSON members): a 48² still Cornell box
  cat > "$1" <<JSON
{"name": "fg-e2e", "scene": "$SRC/scenes/cornell-box/cornell-box.gltf", "frames": $2, "fps": 4,
 "resolution": [48, 48], "camera": {"node": "Camera"}, "still": true,
 "settings": {"shadow_map_size": 256, "photon_count": 4096, $3},
 "capture": ["gbuffer.*", "final_gather.*", "indirect.radiance", "composite.radiance"]}
JSON
}
seq_with "$WORK/p.json" 3 '"preset": "interactive", "final_gather_rays": 16, "random": "per-frame"'
"$ISPM" record "$WORK/p.json" -o "$WORK/a" --quiet > /dev/null || fail "record exited $?"
python3 - "$WORK/a/manifest.json" <<'PY' || fail "manifest settings"
import json, sys
s = json.load(open(sys.argv[1]))["settings"]
want = {"preset": "interactive", "indirect": "final-gather", "final_gather_rays": 16,
        "final_gather_seed": "surface", "final_gather_reuse": 16, "splat_subsample": 4, "temporal": True,
        "atrous_iterations": 3, "atrous_detail": "none"}
for k, v in want.items():
    assert s.get(k) == v, f"{k}: {s.get(k)!r}, expected {v!r}"
assert abs(s["final_gather_radius"] - 0.15) < 1e-6 and abs(s["final_gather_cell"] - 0.01) < 1e-6
PY
"$ISPM" replay "$WORK/a" --golden "$WORK/a" --report "$WORK/rep-a" --quiet > "$WORK/rep-a.out" ||
  { cat "$WORK/rep-a.out"; fail "replay of the preset's record exited $?"; }
"$ISPM" record "$WORK/p.json" -o "$WORK/b" --quiet > /dev/null || fail "second record exited $?"
"$ISPM" replay "$WORK/b" --golden "$WORK/a" --report "$WORK/rep-b" > "$WORK/rep-b.out" ||
  { cat "$WORK/rep-b.out"; fail "second record differs"; }
grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/rep-b.out" || { cat "$WORK/rep-b.out"; fail "not bit-exact"; }
# Resume after losing the last frame: the reuse history (per-frame random numbers, so that reused
# light differs from regathered light) is rebuilt silently and the frame ends bit-identical.
cp -r "$WORK/a" "$WORK/c"
rm -f "$WORK/c/manifest.json" "$WORK"/c/frames/000002.{exr,json}
"$ISPM" record "$WORK/p.json" -o "$WORK/c" --resume --quiet > /dev/null || fail "record --resume exited $?"
"$ISPM" replay "$WORK/c" --golden "$WORK/a" --report "$WORK/rep-c" > "$WORK/rep-c.out" ||
  { cat "$WORK/rep-c.out"; fail "resumed record differs"; }
grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/rep-c.out" || { cat "$WORK/rep-c.out"; fail "resume not bit-exact"; }

# Near-plane walk (scenes/stress/near-plane.json): surface seeds flicker less than pixel seeds.
flicker() { # flicker SETTINGS LABEL -> reprojected mean of indirect.radiance
  python3 - "$SRC/scenes/stress/near-plane.json" "$WORK/np-$2.json" "$1" <<'PY'
import json, os, sys
s = json.load(open(sys.argv[1]))
s["scene"] = os.path.abspath(os.path.join(os.path.dirname(sys.argv[1]), s["scene"]))
s["settings"].update(json.loads("{" + sys.argv[3] + "}"))
s["resolution"] = [48, 48]
s["capture"] = ["gbuffer.*", "indirect.radiance"]
json.dump(s, open(sys.argv[2], "w"))
PY
  "$ISPM" record "$WORK/np-$2.json" -o "$WORK/np-$2" --quiet > /dev/null || fail "near-plane $2: record exited $?"
  "$ISPM" replay "$WORK/np-$2" --report "$WORK/np-rep-$2" --no-flip --quiet > /dev/null
  python3 -c "
import json, sys
st = json.load(open(sys.argv[1]))['stability']
print(next(b for b in st['buffers'] if b['name'] == 'indirect.radiance')['reprojected']['mean'])" \
    "$WORK/np-rep-$2/report.json" || fail "near-plane $2: no stability measure"
}
fp=$(flicker '"indirect": "final-gather", "final_gather_rays": 16' pixel)
fs=$(flicker '"indirect": "final-gather", "final_gather_rays": 16, "final_gather_seed": "surface", "final_gather_cell": 0.05' surface)
echo "near-plane reprojected flicker of indirect.radiance: pixel seeds $fp, surface seeds $fs"
awk -v p="$fp" -v s="$fs" 'BEGIN { exit !(s < 0.8 * p) }' || fail "surface seeds flicker $fs, pixel seeds $fp"

# Bad input: one line naming the file, exit 2, no run.
seq_with "$WORK/bad.json" 1 '"preset": "fastest"'
"$ISPM" record "$WORK/bad.json" -o "$WORK/bad" --quiet > /dev/null 2> "$WORK/bad.err"; rc=$?
[ $rc -eq 2 ] || fail "bad preset: exit $rc"
[ "$(wc -l < "$WORK/bad.err")" -eq 1 ] && grep -q "bad.json" "$WORK/bad.err" && grep -q "preset" "$WORK/bad.err" ||
  { cat "$WORK/bad.err"; fail "bad preset: message"; }
[ ! -f "$WORK/bad/manifest.json" ] || fail "bad preset: a manifest was written"

# Textured surfaces the gather rays reach are shaded with their textures: on the atrium (marble
# and sandstone whose base colour factor is 1 over darker textures) the final gather's mean
# indirect radiance is the path-traced reference's within 10 % per channel (shaded with the
# factor alone it was 2-3.5 times brighter).
python3 - "$SRC/scenes/atrium/atrium-ci.json" "$SRC/scenes/atrium/atrium.gltf" "$WORK/atrium.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s.update(name="fg-atrium", scene=sys.argv[2], frames=1, capture=["indirect.radiance"])
s["settings"]["indirect"] = "final-gather"
json.dump(s, open(sys.argv[3], "w"))
PY
"$ISPM" record "$WORK/atrium.json" -o "$WORK/atr" --quiet > /dev/null 2>&1 || fail "atrium final gather: record"
"$ISPM" reference "$WORK/atrium.json" -o "$WORK/atr-ref" --spp 64 --quiet > /dev/null 2>&1 || fail "atrium: reference"
"$ISPM" export "$WORK/atr" --frame 0 --buffer indirect.radiance -o "$WORK/atr.exr" > /dev/null || fail "export"
"$ISPM" export "$WORK/atr-ref" --frame 0 --buffer reference.indirect -o "$WORK/atr-ref.exr" > /dev/null || fail "export"
python3 - "$WORK/atr.exr" "$WORK/atr-ref.exr" <<'PY' || fail "atrium: final gather against the reference"
import subprocess, sys
def means(f):
    out = subprocess.run(["oiiotool", "--stats", f], capture_output=True, text=True).stdout
    line = next(l for l in out.splitlines() if "Stats Avg" in l)
    return [float(x) for x in line.split(":")[1].split()[:3]]
fg, ref = means(sys.argv[1]), means(sys.argv[2])
print("atrium mean indirect radiance: final gather %s, reference %s" % (fg, ref))
sys.exit(0 if all(abs(a / b - 1) <= 0.10 for a, b in zip(fg, ref)) else 1)
PY

for c in final-gather final-gather-16 final-gather-atrium; do
  "$ISPM" bench --check "$SRC/bench/$c.json" > /dev/null 2>&1 || fail "bench/$c.json is not valid"
done
echo "e2e_final_gather: ok"
