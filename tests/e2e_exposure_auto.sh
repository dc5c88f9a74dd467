#!/usr/bin/env bash
# `"exposure": "auto"` at the command line: a floor under a Blender-style light of intensity 1000
# clips at the default exposure (warned); with "auto" no frame is warned, the manifest records
# the stops ("exposure_auto": true; per frame "exposure") and they are log2(0.18 / L) for the
# log-average luminance L of frame 0's lit pixels (recomputed here from composite.radiance), and
# frame 0's final.display uses them as every later frame does; the run replays against itself
# bit-exact; record --resume reuses the recorded stops (a tampered record changes the resumed
# frames; an untouched one gives bit-identical buffers); a shard that starts after frame 0
# meters frame 0 and matches, and two shards merge into the whole run; an unlit floor falls back to 0 stops with one warning; any other
# word is one line naming the key, exit 2.
# usage: e2e_exposure_auto.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
command -v oiiotool > /dev/null || { echo "SKIP: oiiotool is not installed"; exit 77; }
# A 2 m floor quad at y = 0 facing up (positions and indices in a data URI).
B64=$(python3 -c "
import struct, base64
p = struct.pack('<12f', -1,0,-1, 1,0,-1, 1,0,1, -1,0,1) + struct.pack('<6H', 0,2,1, 0,3,2)
print(base64.b64encode(p).decode())")
printf '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]},
  {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],
 "bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
 "buffers":[{"byteLength":60,"uri":"data:application/octet-stream;base64,%s"}],
 "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.4,1]}}]}\n' "$B64" > "$WORK/floor.gltf"
seqf() { # seqf FILE EXPOSURE LIGHTS
  printf '{"scene": "floor.gltf", "frames": 4, "fps": 2, "resolution": [40, 30],
 "camera": {"keys": [{"time": 0, "position": [0, 2.5, 0.5], "target": [0, 0, 0]},
                     {"time": 2, "position": [0.6, 2.0, 1.2], "target": [0, 0, 0]}]}%s,
 "settings": {"shadow_map_size": 64, "photon_count": 1024, "threads": 2, "temporal": true, "exposure": %s},
 "capture": ["composite.radiance", "final.display"]}\n' "$3" "$2" > "$1"
}
LIGHT=', "lights": [{"type": "point", "position": [0.3, 1, 0], "intensity": 1000}]'
record() { # record NAME [ARGS...] -> exit status; stderr in NAME.err
  local n=$1; shift
  "$ISPM" record "$WORK/$n.json" -o "$WORK/$n" --quiet "$@" > /dev/null 2> "$WORK/$n.err"
}
resume() { # resume NAME: record --resume of auto.json into NAME
  "$ISPM" record "$WORK/auto.json" -o "$WORK/$1" --resume --quiet > /dev/null 2> "$WORK/$1.err"
}
digests() { # digests RUN: one line per frame, its buffers' digests
  python3 -c 'import json,sys
for f in json.load(open(sys.argv[1]))["frames"]:
    print(" ".join(b["name"] + "=" + b["digest"] for b in f["buffers"]))' "$1/manifest.json"
}

# ---- the default exposure clips (the scene is what the setting is for)
seqf "$WORK/fixed.json" 0 "$LIGHT"
record fixed || { cat "$WORK/fixed.err"; fail "record at exposure 0"; }
grep -q "warning: frame 0: final.display has .*% of its pixels clipped" "$WORK/fixed.err" ||
  { cat "$WORK/fixed.err"; fail "the scene does not clip at exposure 0"; }

# ---- "auto": no warning, the stops recorded, and they are what frame 0's pixels give
seqf "$WORK/auto.json" '"auto"' "$LIGHT"
record auto || { cat "$WORK/auto.err"; fail "record with exposure auto"; }
[ ! -s "$WORK/auto.err" ] || { cat "$WORK/auto.err"; fail "stderr not empty with exposure auto (--quiet)"; }
grep -q '"exposure":	"auto"' "$WORK/auto/run.json" || fail "run.json does not say \"auto\""
"$ISPM" export "$WORK/auto" --frame 0 --buffer composite.radiance -o "$WORK/r0.exr" || fail "export radiance"
"$ISPM" export "$WORK/auto" --frame 0 --buffer final.display -o "$WORK/d0.exr" || fail "export display"
oiiotool --dumpdata "$WORK/r0.exr" > "$WORK/r0.txt" || fail "oiiotool r0"
oiiotool --dumpdata "$WORK/d0.exr" > "$WORK/d0.txt" || fail "oiiotool d0"
python3 - "$WORK/auto/manifest.json" "$WORK/r0.txt" "$WORK/d0.txt" <<'PY' || fail "the recorded exposure is not frame 0's key value"
import json, math, re, struct, sys
m = json.load(open(sys.argv[1]))
st = m["settings"]
assert st.get("exposure_auto") is True and isinstance(st["exposure"], (int, float)), st
stops = st["exposure"]
f32 = lambda x: struct.unpack("<f", struct.pack("<f", x))[0]
for f in m["frames"]:
    assert f32(f["exposure"]) == f32(stops), (f["index"], f["exposure"], stops)
px = lambda p: [[float(v) for v in l.split(":")[1].split()] for l in open(p) if "Pixel (" in l]
rad, disp = px(sys.argv[2]), px(sys.argv[3])
ys = [0.2126 * r + 0.7152 * g + 0.0722 * b for r, g, b in rad]
lit = [y for y in ys if y > 0]
key = math.exp(sum(math.log(1e-6 + y) for y in lit) / len(lit))
want = math.log2(0.18 / key)
print("e2e_exposure_auto: %d of %d pixels lit, log-average %.4f, %.5f stops (recorded %.5f)" % (len(lit), len(ys), key, want, stops))
assert abs(want - stops) < 1e-3 and stops < -4, (want, stops)
# frame 0's display is its radiance at those stops, not at 0
enc = lambda c: 12.92 * c if c < 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
err = max(abs(enc(min(max(c * 2 ** stops, 0.0), 1.0)) - d) for pr, pd in zip(rad, disp) for c, d in zip(pr, pd))
clipped = sum(1 for p in disp if min(p) >= 1 - 0.5 / 255) / len(disp)
print("e2e_exposure_auto: frame 0 display vs radiance at the stops: max diff %.2e; clipped %.1f %%" % (err, 100 * clipped))
assert err < 2e-3 and clipped < 0.05
PY
"$ISPM" replay "$WORK/auto" --golden "$WORK/auto" > "$WORK/self.replay" 2>&1 ||
  { cat "$WORK/self.replay"; fail "replay against itself"; }
grep -q "replay: OK — 0 failed, 0 warned, 0 within tolerance, 8 bit-exact" "$WORK/self.replay" ||
  { tail -3 "$WORK/self.replay"; fail "replay against itself is not bit-exact"; }

# ---- --resume: the recorded stops are reused, bit for bit
interrupt() { # interrupt NAME: a copy of auto killed after frame 1
  rm -rf "$WORK/$1"; cp -r "$WORK/auto" "$WORK/$1"; rm -rf "$WORK/$1/replay"
  rm -f "$WORK/$1/manifest.json" "$WORK/$1"/frames/00000[23].*
}
interrupt resumed
resume resumed || { cat "$WORK/resumed.err"; fail "record --resume"; }
[ "$(digests "$WORK/resumed")" = "$(digests "$WORK/auto")" ] || fail "--resume is not bit-identical to the whole run"
cmp -s <(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["settings"])' "$WORK/auto/manifest.json") \
       <(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["settings"])' "$WORK/resumed/manifest.json") ||
  fail "--resume records other settings"
interrupt tampered # the recorded stops, one stop brighter: the resumed frames must follow them
python3 - "$WORK/tampered/frames" <<'PY' || fail "tamper"
import json, sys
for n in ("000000", "000001"):
    p = "%s/%s.json" % (sys.argv[1], n); o = json.load(open(p)); o["exposure"] += 1; json.dump(o, open(p, "w"))
PY
resume tampered || { cat "$WORK/tampered.err"; fail "record --resume (tampered)"; }
python3 - "$WORK/auto/manifest.json" "$WORK/tampered/manifest.json" <<'PY' || fail "--resume did not reuse the recorded stops"
import json, sys
a, t = (json.load(open(p)) for p in sys.argv[1:])
assert abs(t["settings"]["exposure"] - a["settings"]["exposure"] - 1) < 1e-5, (a["settings"], t["settings"])
for i in (2, 3):
    da = {b["name"]: b["digest"] for b in a["frames"][i]["buffers"]}
    dt = {b["name"]: b["digest"] for b in t["frames"][i]["buffers"]}
    assert da["composite.radiance"] == dt["composite.radiance"] and da["final.display"] != dt["final.display"], i
PY

# ---- a shard after frame 0 meters frame 0 itself: the same stops and pixels
shard() { # shard NAME A-B: a shard of auto.json, the frame before A written too (merge checks it)
  "$ISPM" record "$WORK/auto.json" -o "$WORK/$1" --frames "$2" --overlap 1 --quiet > /dev/null 2> "$WORK/$1.err"
}
shard shard 2-3 || { cat "$WORK/shard.err"; fail "record a shard"; }
[ "$(digests "$WORK/shard")" = "$(digests "$WORK/auto" | tail -3)" ] || fail "the shard's frames differ from the whole run's"
shard shard0 0-1 || { cat "$WORK/shard0.err"; fail "record the first shard"; }
"$ISPM" merge "$WORK/shard0" "$WORK/shard" -o "$WORK/merged" > "$WORK/merge.out" 2>&1 || { cat "$WORK/merge.out"; fail "merge"; }
[ "$(digests "$WORK/merged")" = "$(digests "$WORK/auto")" ] || fail "the merged shards differ from the whole run"
python3 -c 'import json,sys; a,b=(json.load(open(p))["settings"] for p in sys.argv[1:]); sys.exit(0 if a==b else 1)' \
  "$WORK/auto/manifest.json" "$WORK/merged/manifest.json" || fail "the merged run records other settings"

# ---- nothing lit: 0 stops, one warning (besides the black-frame warnings)
seqf "$WORK/dark.json" '"auto"' ""
record dark || { cat "$WORK/dark.err"; fail "record an unlit floor"; }
grep -q 'warning: .*dark.json: "exposure": "auto": frame 0 has no lit pixel to meter; exposure 0 stops' "$WORK/dark.err" ||
  { cat "$WORK/dark.err"; fail "no warning for an unlit frame 0"; }
python3 -c 'import json,sys; s=json.load(open(sys.argv[1]))["settings"]; sys.exit(0 if s["exposure"]==0 and s["exposure_auto"] else 1)' \
  "$WORK/dark/manifest.json" || fail "an unlit frame 0 does not record 0 stops"

# ---- any other word: one line naming the key, exit 2, no run
seqf "$WORK/bad.json" '"bright"' "$LIGHT"
record bad; rc=$?
[ $rc -eq 2 ] || { cat "$WORK/bad.err"; fail "exit $rc for \"bright\", want 2"; }
[ "$(wc -l < "$WORK/bad.err")" -eq 1 ] && grep -q 'settings.exposure: expected a number or "auto"' "$WORK/bad.err" ||
  { cat "$WORK/bad.err"; fail "the refusal of \"bright\" is not one line naming the key"; }
[ ! -e "$WORK/bad/manifest.json" ] || fail "a manifest was written for a refused sequence"
echo "e2e_exposure_auto: OK"
