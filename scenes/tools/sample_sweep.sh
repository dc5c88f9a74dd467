#!/usr/bin/env bash
# sample_sweep.sh — records every glTF/GLB model under a folder once and says what became of it
# (issue 17's goal: every valid sample model loads and renders; an invalid one gets one line
# and exit 2; no scene renders black without saying why).
#
#   scenes/tools/sample_sweep.sh MODELS_DIR [WORK_DIR]
#
# Per model (sorted by path) a one-frame sequence is written into WORK_DIR (default
# /tmp/ispm-sweep): 128×128, 2048 photons, 256² shadow maps, the model's first perspective
# camera node, else a look-at camera framing the default scene's bounds (POSITION min/max
# through the node transforms); a directional light is added when the model has no
# KHR_lights_punctual light. `ispm record` runs it (ISPM env var: the binary, default
# build/cli/ispm), final.display is exported as a PNG and decoded, and one line is printed:
#
#   loaded    PATH  [mean 0.123]  warnings N: first warning
#   rejected  PATH  exit E: the one-line error
#   black     PATH  (every final.display pixel 0) warnings N: ...
#   crashed   PATH  exit E (a signal, or an exit other than 0/1/2)
#
# then the counts. Needs python3 (standard library only). The models are not part of the
# repository: fetch them yourself (e.g. KhronosGroup/glTF-Sample-Assets' Models/ folder).
set -u
models=${1:?usage: sample_sweep.sh MODELS_DIR [WORK_DIR]}
work=${2:-/tmp/ispm-sweep}
here=$(cd "$(dirname "$0")" && pwd)
ispm=${ISPM:-$here/../../build/cli/ispm}
[ -x "$ispm" ] || { echo "sample_sweep: $ispm is not built (set ISPM)" >&2; exit 2; }
mkdir -p "$work"

# Writes the sequence for model $1 to $2; prints "camera:<how> light:<how>".
make_sequence() {
    python3 - "$1" "$2" <<'PY'
import json, math, struct, sys
path, out = sys.argv[1], sys.argv[2]
def load(path):
    data = open(path, 'rb').read()
    if data[:4] == b'glTF':
        n = struct.unpack_from('<I', data, 12)[0]
        return json.loads(data[20:20 + n])
    return json.loads(data)
try:
    g = load(path)
except Exception as e:  # the recorder reports the error itself
    g = {}
nodes = g.get('nodes', [])
def local(n):
    if 'matrix' in n:
        m = n['matrix']
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    t = n.get('translation', [0, 0, 0]); q = n.get('rotation', [0, 0, 0, 1]); s = n.get('scale', [1, 1, 1])
    x, y, z, w = q
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return [[r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]] for i in range(3)] + [[0, 0, 0, 1]]
def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]
lo, hi = [math.inf] * 3, [-math.inf] * 3
camera_node, has_light = None, False
scenes = g.get('scenes', [])
roots = scenes[g.get('scene', 0)].get('nodes', []) if scenes else [i for i in range(len(nodes))]
stack = [(r, [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) for r in roots]
seen = set()
while stack:
    i, parent = stack.pop()
    if not isinstance(i, int) or i < 0 or i >= len(nodes) or i in seen:
        continue
    seen.add(i)
    n = nodes[i]
    try:
        w = mul(parent, local(n))
    except Exception:
        continue
    cam = n.get('camera')
    if camera_node is None and isinstance(cam, int) and cam < len(g.get('cameras', [])) \
            and g['cameras'][cam].get('type') == 'perspective':
        camera_node = i
    if 'KHR_lights_punctual' in n.get('extensions', {}):
        has_light = True
    mesh = n.get('mesh')
    if isinstance(mesh, int) and mesh < len(g.get('meshes', [])):
        for p in g['meshes'][mesh].get('primitives', []):
            a = p.get('attributes', {}).get('POSITION')
            acc = g.get('accessors', [])
            if not isinstance(a, int) or a >= len(acc) or 'min' not in acc[a] or 'max' not in acc[a]:
                continue
            mn, mx = acc[a]['min'], acc[a]['max']
            for c in range(8):
                v = [mx[k] if c >> k & 1 else mn[k] for k in range(3)]
                q = [sum(w[r][k] * v[k] for k in range(3)) + w[r][3] for r in range(3)]
                for k in range(3):
                    lo[k] = min(lo[k], q[k]); hi[k] = max(hi[k], q[k])
    for c in n.get('children', []):
        stack.append((c, w))
seq = {'name': 'sweep', 'scene': path, 'frames': 1, 'fps': 1, 'resolution': [128, 128],
       'settings': {'photon_count': 2048, 'shadow_map_size': 256, 'threads': 2},
       'capture': ['final.display']}
how = []
if camera_node is not None:
    seq['camera'] = {'node': camera_node}
    how.append('camera:node%d' % camera_node)
else:
    if not all(math.isfinite(x) for x in lo + hi):
        lo, hi = [-1, -1, -1], [1, 1, 1]
    c = [(lo[k] + hi[k]) / 2 for k in range(3)]
    r = max(1e-3, 0.5 * math.sqrt(sum((hi[k] - lo[k]) ** 2 for k in range(3))))
    d = [0.5, 0.35, 0.8]; dl = math.sqrt(sum(x * x for x in d)); dist = r / math.sin(math.radians(20)) * 1.05
    pos = [c[k] + d[k] / dl * dist for k in range(3)]
    seq['camera'] = {'keys': [{'time': 0, 'position': pos, 'target': c}], 'yfov_deg': 40,
                     'znear': max(1e-4, dist - 2 * r) * 0.5, 'zfar': (dist + 2 * r) * 2}
    how.append('camera:framed r=%.3g' % r)
if not has_light:
    seq['lights'] = [{'type': 'directional', 'direction': [-0.4, -1.0, -0.6], 'intensity': 3}]
    how.append('light:added')
else:
    how.append('light:own')
json.dump(seq, open(out, 'w'), indent=1)
print(' '.join(how))
PY
}

# Mean and max of a PNG's RGB (8-bit RGB or RGBA, as ispm export writes), 0..1.
png_stats() {
    python3 - "$1" <<'PY'
import struct, sys, zlib
d = open(sys.argv[1], 'rb').read()
pos, idat, w = 8, b'', 0
while pos < len(d):
    n, t = struct.unpack_from('>I4s', d, pos)
    if t == b'IHDR':
        w, h, bits, ct = struct.unpack_from('>IIBB', d, pos + 8)
    elif t == b'IDAT':
        idat += d[pos + 8:pos + 8 + n]
    pos += 12 + n
bpp = 4 if ct == 6 else 3
raw, stride = zlib.decompress(idat), w * bpp
prev, rows, i = bytearray(stride), [], 0
for y in range(h):
    f, line = raw[i], bytearray(raw[i + 1:i + 1 + stride]); i += 1 + stride
    for x in range(stride):
        a = line[x - bpp] if x >= bpp else 0; b = prev[x]; c = prev[x - bpp] if x >= bpp else 0
        if f == 1: line[x] = (line[x] + a) & 255
        elif f == 2: line[x] = (line[x] + b) & 255
        elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line); prev = line
vals = [r[x] for r in rows for x in range(stride) if x % bpp < 3]
print('%.4f %.4f' % (sum(vals) / len(vals) / 255, max(vals) / 255))
PY
}

loaded=0 rejected=0 black=0 crashed=0 warned=0
while IFS= read -r -d '' model; do
    rel=${model#"$models"/}
    id=$(printf '%s' "$rel" | tr '/ ' '__')
    seq="$work/$id.json" run="$work/$id.run"
    how=$(make_sequence "$model" "$seq")
    rm -rf "$run"
    "$ispm" record "$seq" -o "$run" --quiet >"$work/$id.out" 2>"$work/$id.err"
    rc=$?
    nwarn=$(grep -c 'warning' "$work/$id.err")
    firstwarn=$(grep -m1 'warning' "$work/$id.err" | sed 's/^ispm record: warning: //' | cut -c1-150)
    [ "$nwarn" -gt 0 ] && warned=$((warned + 1))
    wtxt=""
    [ "$nwarn" -gt 0 ] && wtxt="  warnings $nwarn: $firstwarn"
    if [ "$rc" = 2 ] || [ "$rc" = 1 ]; then
        rejected=$((rejected + 1))
        printf 'rejected  %s  exit %d: %s\n' "$rel" "$rc" "$(grep -v warning "$work/$id.err" | head -1 | cut -c1-200)"
    elif [ "$rc" != 0 ]; then
        crashed=$((crashed + 1))
        printf 'crashed   %s  exit %d: %s\n' "$rel" "$rc" "$(tail -1 "$work/$id.err" | cut -c1-200)"
    elif ! "$ispm" export "$run" --frame 0 --buffer final.display -o "$work/$id.png" >/dev/null 2>&1; then
        crashed=$((crashed + 1))
        printf 'crashed   %s  export of final.display failed\n' "$rel"
    else
        read -r mean max < <(png_stats "$work/$id.png")
        if [ "$max" = "0.0000" ]; then
            black=$((black + 1))
            printf 'black     %s  (%s)%s\n' "$rel" "$how" "$wtxt"
        else
            loaded=$((loaded + 1))
            printf 'loaded    %s  mean %s (%s)%s\n' "$rel" "$mean" "$how" "$wtxt"
        fi
    fi
done < <(find "$models" -type f \( -name '*.gltf' -o -name '*.glb' \) -print0 | sort -z)
total=$((loaded + rejected + black + crashed))
printf 'summary: %d models: %d loaded and rendered, %d rejected, %d black, %d crashed; %d with warnings\n' \
    "$total" "$loaded" "$rejected" "$black" "$crashed" "$warned"
