#!/usr/bin/env bash
# Real glTF files at the command line: a frame whose final.display is all black or clipped is
# a warning on stderr, in the frame's manifest record and in replay's report.txt, report.json
# and report.html; a sequence without camera frames the scene (the floor fills the view, no
# warning); EXT_texture_webp read from a .webp beside the glTF, and its PNG fallback where
# the WebP does not decode; glTF 1.0, an unknown required extension and a scene without
# geometry are one line naming the file and the feature, exit 2, no run.
# usage: e2e_gltf_ext.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK/scene"
# A 2 m floor quad at y = 0 facing up with UVs (positions, UVs, indices in a data URI).
B64=$(python3 -c "
import struct, base64
p = struct.pack('<12f', -1,0,-1, 1,0,-1, 1,0,1, -1,0,1) + struct.pack('<8f', 0,0, 1,0, 1,1, 0,1) + struct.pack('<6H', 0,2,1, 0,3,2)
print(base64.b64encode(p).decode())")
gltf() { # gltf FILE MATERIAL_MEMBERS ROOT_MEMBERS
  printf '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,"material":0}]}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]},
  {"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"},
  {"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}],
 "bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":32},
  {"buffer":0,"byteOffset":80,"byteLength":12}],
 "buffers":[{"byteLength":92,"uri":"data:application/octet-stream;base64,%s"}],
 "materials":[{%s}]%s}\n' "$B64" "$2" "$3" > "$1"
}
seqf() { # seqf FILE SCENE CAMERA_MEMBER EXTRA
  printf '{"scene": "%s", "frames": 1, "fps": 1, "resolution": [32, 24]%s,
 "settings": {"shadow_map_size": 32, "photon_count": 256, "threads": 2},
 "capture": ["final.display"]%s}\n' "$2" "$3" "$4" > "$1"
}
record() { # record NAME -> exit status; stderr in NAME.err
  "$ISPM" record "$WORK/$1.json" -o "$WORK/$1" --quiet > /dev/null 2> "$WORK/$1.err"
}
TOP=', "camera": {"keys": [{"time": 0, "position": [0, 3, 0.01], "target": [0, 0, 0]}]}'
gltf "$WORK/scene/floor.gltf" '"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1]}' ""

# ---- no light: all black, warned everywhere
seqf "$WORK/dark.json" "scene/floor.gltf" "$TOP" ""
record dark || { cat "$WORK/dark.err"; fail "record without light"; }
grep -q "warning: frame 0: final.display is all black" "$WORK/dark.err" || { cat "$WORK/dark.err"; fail "no black-frame warning on stderr"; }
python3 -c 'import json,sys; f=json.load(open(sys.argv[1]))["frames"][0]; sys.exit(0 if "all black" in f.get("display_warning","") else 1)' \
  "$WORK/dark/manifest.json" || fail "no display_warning in the manifest's frame record"
"$ISPM" replay "$WORK/dark" > "$WORK/dark.replay" 2>&1
grep -q "display warning: run frame 0: final.display is all black" "$WORK/dark.replay" || { cat "$WORK/dark.replay"; fail "replay does not show the display warning"; }
python3 -c 'import json,sys; d=json.load(open(sys.argv[1]))["display_warnings"]; sys.exit(0 if d[0]["side"]=="run" and d[0]["frame"]==0 else 1)' \
  "$WORK/dark/replay/report.json" || fail "report.json lacks display_warnings"
if [ -f "$WORK/dark/replay/report.html" ]; then
  grep -q "display warning" "$WORK/dark/replay/report.html" || fail "report.html lacks the display warning"
fi
# against a golden that is the same run: both sides' warnings are shown
"$ISPM" replay "$WORK/dark" --golden "$WORK/dark" > "$WORK/dark.replay2" 2>&1
grep -q "display warning: golden frame 0" "$WORK/dark.replay2" || { cat "$WORK/dark.replay2"; fail "replay against a golden does not show the golden's warning"; }

# ---- a light of intensity 1000 one metre above: clipped, warned
seqf "$WORK/bright.json" "scene/floor.gltf" "$TOP" ', "lights": [{"type": "point", "position": [0, 1, 0], "intensity": 1000}]'
record bright || { cat "$WORK/bright.err"; fail "record with a bright light"; }
grep -q "warning: frame 0: final.display has .*% of its pixels clipped" "$WORK/bright.err" || { cat "$WORK/bright.err"; fail "no clipping warning"; }

# ---- a moderate light, no camera: the floor is framed and lit, no warning at all
seqf "$WORK/framed.json" "scene/floor.gltf" "" ', "lights": [{"type": "directional", "direction": [0, -1, 0], "intensity": 2}]'
record framed || { cat "$WORK/framed.err"; fail "record without camera"; }
[ ! -s "$WORK/framed.err" ] || { cat "$WORK/framed.err"; fail "stderr not empty for a framed, lit floor"; }
"$ISPM" export "$WORK/framed" --frame 0 --buffer final.display -o "$WORK/framed.png" || fail "export"
python3 - "$WORK/framed/manifest.json" <<'PY' || fail "the framing camera does not look at the floor from the default direction"
import json, math, sys
m = json.load(open(sys.argv[1]))
eye = m["frames"][0]["camera"]["eye"]
d = [-0.35, -0.3, -1.0]; n = math.sqrt(sum(x * x for x in d)); d = [x / n for x in d]
r = math.sqrt(2.0); fov = math.radians(40) / 2
dist = r / math.sin(min(fov, math.atan(math.tan(fov) * 32 / 24)))
want = [-dist * x for x in d]
err = max(abs(a - b) for a, b in zip(eye, want))
print("e2e_gltf_ext: framed eye", eye, "want", want)
sys.exit(0 if err < 1e-4 else 1)
PY

# ---- EXT_texture_webp from files beside the glTF, and the PNG fallback
convert -size 4x4 xc:'#00ff00' -define webp:lossless=true "$WORK/scene/green.webp" || fail "convert webp"
convert -size 4x4 xc:'#ff0000' "PNG24:$WORK/scene/red.png" || fail "convert png"
printf 'not a webp' > "$WORK/scene/broken.webp"
tex='"pbrMetallicRoughness":{"baseColorTexture":{"index":0}},"emissiveFactor":[1,1,1],"emissiveTexture":{"index":0}'
webp() { # webp FILE WEBP_URI
  gltf "$1" "$tex" ',"extensionsUsed":["EXT_texture_webp"],"textures":[{"source":0,"extensions":{"EXT_texture_webp":{"source":1}}}],
 "images":[{"uri":"red.png"},{"uri":"'"$2"'"}]'
}
webp "$WORK/scene/webp.gltf" green.webp
webp "$WORK/scene/fallback.gltf" broken.webp
for name in webp fallback; do
  seqf "$WORK/$name.json" "scene/$name.gltf" "$TOP" ""
  record $name || { cat "$WORK/$name.err"; fail "record $name"; }
  oiiotool -a --stats "$WORK/$name/frames/000000.exr" > "$WORK/$name.stats" 2>&1 || fail "oiiotool $name"
done
grep -q "fallback source, image 0, is used" "$WORK/fallback.err" || { cat "$WORK/fallback.err"; fail "no warning for the WebP fallback"; }
python3 - "$WORK/webp.stats" "$WORK/fallback.stats" <<'PY' || fail "the WebP (green) or its fallback (red) is not what the floor shows"
import re, sys
def avg(p):
    m = re.search(r"Stats Avg:\s*([-\d.e]+)\s+([-\d.e]+)\s+([-\d.e]+)", open(p).read())
    return [float(x) for x in m.groups()]
g, r = avg(sys.argv[1]), avg(sys.argv[2])
print("e2e_gltf_ext: webp avg", g, "fallback avg", r)
sys.exit(0 if g[1] > 2 * g[0] and r[0] > 2 * r[1] else 1)
PY

# ---- refusals: one line naming the file and the feature, exit 2, no manifest
refuse() { # refuse NAME WORD
  seqf "$WORK/$1.json" "scene/$1.gltf" "$TOP" ""
  record "$1"; rc=$?
  [ $rc -eq 2 ] || { cat "$WORK/$1.err"; fail "$1: exit $rc, want 2"; }
  [ "$(wc -l < "$WORK/$1.err")" -eq 1 ] || { cat "$WORK/$1.err"; fail "$1: want one line on stderr"; }
  grep -q "$1.gltf: .*$2" "$WORK/$1.err" || { cat "$WORK/$1.err"; fail "$1: the error does not say $2"; }
  [ ! -e "$WORK/$1/manifest.json" ] || fail "$1: a manifest was written"
}
printf '{"asset":{"version":"1.0"},"meshes":{"m":{"primitives":[]}}}\n' > "$WORK/scene/gltf1.gltf"
refuse gltf1 "glTF 1.0"
gltf "$WORK/scene/required.gltf" "" ',"extensionsRequired":["EXT_meshopt_compressionX"],"extensionsUsed":["EXT_meshopt_compressionX"]'
refuse required "extensionsRequired: EXT_meshopt_compressionX is not supported"
printf '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"name":"empty"}]}\n' > "$WORK/scene/empty.gltf"
refuse empty "no geometry"
echo "e2e_gltf_ext: ok"
