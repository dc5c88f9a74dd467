#!/usr/bin/env bash
# Real glTF scenes at the command line (issue 17): a scene without any light records with a
# warning on stderr and in the manifest ("warnings"), never silently black; the sequence's
# "lights" light it (no warning, the direct light differs); a buffer URI that leaves the
# scene's folder, names a directory or a missing file is one line on stderr and exit 2; an
# animated skinned model moves its G-buffer positions and its motion vectors follow the skin.
# usage: e2e_gltf.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK/scene/a-dir"
# A 2 m floor quad at y = 0 facing up, 4 vertices and 6 indices in a data URI, no light.
B64=$(python3 -c "
import struct, base64
p = struct.pack('<12f', -1,0,-1, 1,0,-1, 1,0,1, -1,0,1) + struct.pack('<6H', 0,2,1, 0,3,2)
print(base64.b64encode(p).decode())")
gltf() { # gltf FILE URI
  printf '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"},
  {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],
 "bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
 "buffers":[{"byteLength":60,"uri":"%s"}]}\n' "$2" > "$1"
}
seqf() { # seqf FILE SCENE EXTRA
  printf '{"scene": "%s", "frames": 1, "fps": 1, "resolution": [16, 12],
 "camera": {"keys": [{"time": 0, "position": [0, 2, 2], "target": [0, 0, 0]}]},
 "settings": {"shadow_map_size": 16, "photon_count": 256, "threads": 2},
 "capture": ["direct.radiance", "final.display"]%s}\n' "$2" "$3" > "$1"
}
gltf "$WORK/scene/floor.gltf" "data:application/octet-stream;base64,$B64"

# ---- no light: exit 0, one warning on stderr, "warnings" in the manifest
seqf "$WORK/dark.json" "scene/floor.gltf" ""
"$ISPM" record "$WORK/dark.json" -o "$WORK/dark" --quiet > /dev/null 2> "$WORK/dark.err" || { cat "$WORK/dark.err"; fail "record without light"; }
grep -q "warning: no light" "$WORK/dark.err" || { cat "$WORK/dark.err"; fail "no warning on stderr for a scene without light"; }
python3 - "$WORK/dark/manifest.json" <<'PY' || fail "the manifest lacks the no-light warning"
import json, sys
w = json.load(open(sys.argv[1])).get("warnings", [])
sys.exit(0 if any("no light" in x for x in w) else 1)
PY

# ---- the sequence adds a light: no warning, and the direct light is no longer black
seqf "$WORK/lit.json" "scene/floor.gltf" ', "lights": [{"type": "point", "position": [0, 1, 0], "intensity": 4}]'
"$ISPM" record "$WORK/lit.json" -o "$WORK/lit" --quiet > /dev/null 2> "$WORK/lit.err" || { cat "$WORK/lit.err"; fail "record with a sequence light"; }
[ ! -s "$WORK/lit.err" ] || { cat "$WORK/lit.err"; fail "stderr not empty with a sequence light"; }
python3 - "$WORK/dark/manifest.json" "$WORK/lit/manifest.json" <<'PY' || fail "the sequence light changed nothing"
import json, sys
dig = [{b["name"]: b["digest"] for b in json.load(open(p))["frames"][0]["buffers"]} for p in sys.argv[1:]]
m = json.load(open(sys.argv[2]))
sys.exit(0 if dig[0]["direct.radiance"] != dig[1]["direct.radiance"] and "warnings" not in m else 1)
PY

# ---- files stay inside the scene: one line, exit 2, each with its own reason
head -c 60 /dev/zero > "$WORK/outside.bin"
expect() { # expect WORD URI
  gltf "$WORK/scene/bad.gltf" "$2"
  seqf "$WORK/bad.json" "scene/bad.gltf" ""
  "$ISPM" record "$WORK/bad.json" -o "$WORK/bad" --quiet > /dev/null 2> "$WORK/bad.err"; rc=$?
  [ $rc -eq 2 ] || { cat "$WORK/bad.err"; fail "URI $2: exit $rc, want 2"; }
  [ "$(wc -l < "$WORK/bad.err")" -eq 1 ] || { cat "$WORK/bad.err"; fail "URI $2: want one line on stderr"; }
  grep -q "bad.gltf.*$1" "$WORK/bad.err" || { cat "$WORK/bad.err"; fail "URI $2: the error does not say $1"; }
  [ ! -e "$WORK/bad/manifest.json" ] || fail "URI $2: a manifest was written"
}
expect "leaves" "../outside.bin"
expect "absolute" "$WORK/outside.bin"
expect "directory" "a-dir"
expect "no such file" "missing.bin"
expect "data URI" "data:application/octet-stream;base64,AAAA"
ln -s ../outside.bin "$WORK/scene/link.bin"
expect "symbolic link" "link.bin"
# ---- an animated skinned model (issue 17 item 3; tests/data/skin_gltf.py, test_skin.c): the eye
# G-buffer's positions change from frame to frame, and each pixel's motion vector points to
# where the same point of the deformed surface was in the previous frame: the previous
# frame's position bilinearly read there is the analytic pose of that point, within 1e-3 m
# (the surface moves 0.06-0.4 m per frame; a motion vector of the rest pose misses by that).
python3 "$SRC/tests/data/skin_gltf.py" skin > "$WORK/scene/skin.gltf" || fail "skin_gltf.py"
printf '{"scene": "scene/skin.gltf", "frames": 3, "fps": 4, "resolution": [48, 48],
 "camera": {"keys": [{"time": 0, "position": [0, 1, 4], "target": [0, 1, 0]}], "yfov_deg": 60},
 "lights": [{"type": "point", "position": [0, 1, 3]}],
 "settings": {"shadow_map_size": 32, "photon_count": 256, "threads": 2},
 "capture": ["gbuffer.position", "gbuffer.depth", "gbuffer.motion"]}\n' > "$WORK/skin.json"
"$ISPM" record "$WORK/skin.json" -o "$WORK/skin" --quiet > /dev/null 2> "$WORK/skin.err" || { cat "$WORK/skin.err"; fail "record the skinned model"; }
python3 - "$WORK/skin/manifest.json" <<'PY' || fail "gbuffer.position did not change across the frames of the skinned model"
import json, sys
f = json.load(open(sys.argv[1]))["frames"]
d = [{b["name"]: b["digest"] for b in x["buffers"]}["gbuffer.position"] for x in f]
sys.exit(0 if len(d) == 3 and len(set(d)) == 3 else 1)
PY
for fr in 1 2; do oiiotool -a --dumpdata "$WORK/skin/frames/00000$fr.exr" > "$WORK/dump$fr.txt" || fail "oiiotool frame $fr"; done
python3 - "$WORK" <<'PY' || fail "motion vectors do not follow the deformed surface"
import math, re, sys
W = sys.argv[1]; N = 48
def load(fr):  # the frame's parts by channel count: 3 position, 1 depth, 2 motion
    parts, cur = {}, None
    for line in open(f"{W}/dump{fr}.txt"):
        m = re.match(r"\s*Pixel \((\d+), (\d+)\):\s*(.*)", line)
        if m:
            v = [float(x) for x in m.group(3).split()]
            if cur is None or (m.group(1), m.group(2)) == ("0", "0"):
                cur = parts.setdefault(len(v), {})
            cur[(int(m.group(1)), int(m.group(2)))] = v
    return parts
d1, d2 = load(1), load(2)
pos = {1: d1[3], 2: d2[3]}; dep = {1: d1[1], 2: d2[1]}; mot = d2[2]
def pose(t, rest, w_root):  # skin_gltf.py's analytic pose (test_skin.c skin_expected)
    u = min(max(t, 0.0), 1.0); rx = 0.5 * u; th = u * math.pi / 2; c, s = math.cos(th), math.sin(th)
    y = rest[1] - 1.0
    root = (rest[0] + rx, rest[1], rest[2]); tip = (rx + c * rest[0] - s * y, 1.0 + s * rest[0] + c * y, rest[2])
    return [w_root * a + (1 - w_root) * b for a, b in zip(root, tip)]
z = 0.01
rest = [((-.5, 0, 0), 1), ((.5, 0, 0), 1), ((.5, 1, 0), 1), ((-.5, 1, 0), 1),
        ((-.5, 1, z), .5), ((.5, 1, z), .5), ((.5, 2, z), 0), ((-.5, 2, z), 0)]
V = {f: [pose(0.25 * f, r, w) for r, w in rest] for f in (1, 2)}
tris = [(0, 1, 2), (0, 2, 3), (4, 5, 6), (4, 6, 7)]
def bary(a, b, c, x, y):
    d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
    w1 = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / d
    w2 = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / d
    return (1 - w1 - w2, w1, w2)
checked = worst = 0
for (x, y), X in pos[2].items():
    if dep[2][(x, y)][0] <= 0: continue
    part = 1 if X[2] > 0.005 else 0
    for t in tris[2 * part: 2 * part + 2]:
        b = bary(V[2][t[0]], V[2][t[1]], V[2][t[2]], X[0], X[1])
        if min(b) > -1e-4: break
    else: continue
    want = [sum(b[k] * V[1][t[k]][c] for k in range(3)) for c in range(3)]
    px, py = x + mot[(x, y)][0], y + mot[(x, y)][1]
    x0, y0 = math.floor(px), math.floor(py)
    taps = [(x0 + i, y0 + j) for j in (0, 1) for i in (0, 1)]
    if any(tp not in dep[1] or dep[1][tp][0] <= 0 or (pos[1][tp][2] > 0.005) != bool(part) for tp in taps): continue
    ax, ay = px - x0, py - y0
    wts = [(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay]
    got = [sum(w * pos[1][tp][c] for w, tp in zip(wts, taps)) for c in range(3)]
    worst = max(worst, math.dist(got, want)); checked += 1
print(f"e2e_gltf: skinned model: {checked} pixels reprojected, worst {worst:.3g} m (bound 1e-3)")
sys.exit(0 if checked > 100 and worst <= 1e-3 else 1)
PY
echo "e2e_gltf: ok"
