#!/usr/bin/env python3
"""Writes scenes/caustic-ring/caustic-ring.gltf: the cardioid caustic of ISPM Fig. 5.

A mirror ring (a cylindrical band, 300 degrees of arc so its rotation is visible, radius 0.5 m,
height 0.25 m, metallic 1, roughness 0, base colour 0.95) on a diffuse floor (4 m x 4 m,
albedo 0.8) under a spot light low on one side aimed at the ring's centre. Light reflected
off the inside of the band focuses into a cardioid on the floor. The ring turns about Y by
30 degrees per second (animation "spin"). Stdlib only; the output is committed."""
import base64, json, math, struct, sys

SEG = 96          # segments over the arc
ARC = math.radians(300.0)
R, H = 0.5, 0.25

def ring():
    pos, nrm, idx = [], [], []
    for i in range(SEG + 1):
        a = -ARC / 2 + ARC * i / SEG
        c, s = math.cos(a), math.sin(a)
        for y in (0.0, H):
            pos.append((R * c, y, R * s))
            nrm.append((-c, 0.0, -s))  # modelled facing the centre; double-sided
    for i in range(SEG):
        a, b, c, d = 2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3
        idx += [a, b, c, c, b, d]
    return pos, nrm, idx

def floor():
    pos = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)]
    nrm = [(0, 1, 0)] * 4
    return pos, nrm, [0, 2, 1, 0, 3, 2]

data = bytearray()
views, accessors, meshes = [], [], []

def add(kind_bytes, target):
    off = len(data)
    data.extend(kind_bytes)
    while len(data) % 4:
        data.append(0)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(kind_bytes), "target": target})
    return len(views) - 1

def mesh(name, pos, nrm, idx, material):
    pv = add(b"".join(struct.pack("<3f", *p) for p in pos), 34962)
    nv = add(b"".join(struct.pack("<3f", *n) for n in nrm), 34962)
    iv = add(b"".join(struct.pack("<I", i) for i in idx), 34963)
    lo = [min(p[k] for p in pos) for k in range(3)]
    hi = [max(p[k] for p in pos) for k in range(3)]
    accessors.append({"bufferView": pv, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi})
    accessors.append({"bufferView": nv, "componentType": 5126, "count": len(nrm), "type": "VEC3"})
    accessors.append({"bufferView": iv, "componentType": 5125, "count": len(idx), "type": "SCALAR"})
    a = len(accessors) - 3
    meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": a, "NORMAL": a + 1}, "indices": a + 2,
                                                 "material": material}]})
    return len(meshes) - 1

mf = mesh("floor", *floor(), 0)
mr = mesh("ring", *ring(), 1)

# Animation: rotation about Y, 0 -> 30 degrees over 1 s (LINEAR).
times = [0.0, 1.0]
rots = []
for t in times:
    half = math.radians(30.0 * t) / 2
    rots.append((0.0, math.sin(half), 0.0, math.cos(half)))
tv = add(b"".join(struct.pack("<f", t) for t in times), None)
rv = add(b"".join(struct.pack("<4f", *q) for q in rots), None)
for v in (tv, rv):
    del views[v]["target"]
accessors.append({"bufferView": tv, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [1.0]})
accessors.append({"bufferView": rv, "componentType": 5126, "count": 2, "type": "VEC4"})
ta, ra = len(accessors) - 2, len(accessors) - 1

# Spot at (-1.4, 1.0, 0) aimed at the ring's centre (0, 0.05, 0): rotate -Z onto that direction.
L = (-1.4, 1.0, 0.0)
d = [0 - L[0], 0.05 - L[1], 0 - L[2]]
n = math.sqrt(sum(x * x for x in d)); d = [x / n for x in d]
# quaternion from (0,0,-1) to d
f = (0.0, 0.0, -1.0)
cx = (f[1] * d[2] - f[2] * d[1], f[2] * d[0] - f[0] * d[2], f[0] * d[1] - f[1] * d[0])
w = 1.0 + sum(a * b for a, b in zip(f, d))
q = [cx[0], cx[1], cx[2], w]
qn = math.sqrt(sum(x * x for x in q)); q = [x / qn for x in q]

doc = {
    "asset": {"version": "2.0", "generator": "ispm scenes/tools/make_caustic_ring.py"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": 8.0,
         "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.5}}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3]}],
    "nodes": [
        {"name": "floor", "mesh": mf},
        {"name": "ring", "mesh": mr},
        {"name": "Spot", "translation": list(L), "rotation": q, "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "Camera", "camera": 0, "translation": [0.0, 2.0, 1.6],
         "rotation": [-math.sin(math.radians(51.34) / 2), 0.0, 0.0, math.cos(math.radians(51.34) / 2)]},
    ],
    "cameras": [{"name": "Camera", "type": "perspective",
                 "perspective": {"yfov": math.radians(45.0), "aspectRatio": 1.0, "znear": 0.05, "zfar": 100.0}}],
    "meshes": meshes,
    "materials": [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0,
                                                   "roughnessFactor": 1}, "doubleSided": True},
        {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.95, 0.95, 1], "metallicFactor": 1,
                                                    "roughnessFactor": 0}, "doubleSided": True},
    ],
    "animations": [{"name": "spin", "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
                    "samplers": [{"input": ta, "output": ra, "interpolation": "LINEAR"}]}],
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(data),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode()}],
}
out = sys.argv[1] if len(sys.argv) > 1 else "caustic-ring.gltf"
with open(out, "w") as fo:
    json.dump(doc, fo, indent=1)
    fo.write("\n")
