#!/usr/bin/env bash
# Real glTF scenes at the command line (issue 17): a scene without any light records with a
# warning on stderr and in the manifest ("warnings"), never silently black; the sequence's
# "lights" light it (no warning, the direct light differs); a buffer URI that leaves the
# scene's folder, names a directory or a missing file is one line on stderr and exit 2.
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
echo "e2e_gltf: ok"
