#!/usr/bin/env python3
"""Writes scenes/cornell-box/cornell-pane.gltf: the Cornell box (cornell-box.gltf) with a
half-transparent blue pane in front of the back wall (issue 14 item 3, alphaMode BLEND).

The pane: a double-sided quad facing +Z at z = -0.7 (the back wall is at z = -1.04),
x in [-0.35, 0.35], y in [1.25, 1.7] (above both boxes), baseColorFactor (0.2, 0.4, 0.9, 0.5),
metallic 0, roughness 1, alphaMode BLEND. Stdlib only; the output is committed.
usage: make_cornell_pane.py [SRC_GLTF [OUT_GLTF]]"""
import base64, json, os, struct, sys

HERE = os.path.dirname(os.path.abspath(__file__))
src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "cornell-box", "cornell-box.gltf")
out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(HERE, "..", "cornell-box", "cornell-pane.gltf")
Z, X0, X1, Y0, Y1 = -0.7, -0.35, 0.35, 1.25, 1.7

g = json.load(open(src))
prefix = "data:application/octet-stream;base64,"
buf = g["buffers"][0]
assert buf["uri"].startswith(prefix), "the source's buffer is not a data URI"
data = bytearray(base64.b64decode(buf["uri"][len(prefix):]))

def add(blob, target):
    while len(data) % 4:
        data.append(0)
    g["bufferViews"].append({"buffer": 0, "byteOffset": len(data), "byteLength": len(blob), "target": target})
    data.extend(blob)
    return len(g["bufferViews"]) - 1

pos = [(X0, Y0, Z), (X1, Y0, Z), (X1, Y1, Z), (X0, Y1, Z)]
nrm = [(0.0, 0.0, 1.0)] * 4
idx = [0, 1, 2, 0, 2, 3]
acc = len(g["accessors"])
g["accessors"] += [
    {"bufferView": add(b"".join(struct.pack("<3f", *p) for p in pos), 34962), "componentType": 5126, "count": 4,
     "type": "VEC3", "min": [X0, Y0, Z], "max": [X1, Y1, Z]},
    {"bufferView": add(b"".join(struct.pack("<3f", *n) for n in nrm), 34962), "componentType": 5126, "count": 4,
     "type": "VEC3"},
    {"bufferView": add(b"".join(struct.pack("<I", i) for i in idx), 34963), "componentType": 5125, "count": 6,
     "type": "SCALAR"},
]
g["materials"].append({"name": "pane", "alphaMode": "BLEND", "doubleSided": True,
                       "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.9, 0.5], "metallicFactor": 0.0,
                                                "roughnessFactor": 1.0}})
g["meshes"].append({"name": "pane", "primitives": [{"attributes": {"POSITION": acc, "NORMAL": acc + 1},
                                                    "indices": acc + 2, "material": len(g["materials"]) - 1}]})
g["nodes"].append({"name": "pane", "mesh": len(g["meshes"]) - 1})
g["scenes"][g.get("scene", 0)]["nodes"].append(len(g["nodes"]) - 1)
buf["byteLength"] = len(data)
buf["uri"] = prefix + base64.b64encode(bytes(data)).decode()
with open(out, "w") as f:
    json.dump(g, f, indent=1)
    f.write("\n")
