#!/usr/bin/env python3
"""obj2gltf.py — converts the Cornell box OBJ/MTL scenes into single-file glTF 2.0.

Usage:
    obj2gltf.py INPUT.obj OUTPUT.gltf [--animate]

The geometry is exactly the OBJ's: every coordinate is the float32 nearest to the OBJ's
decimal text (rounded once, ties to even), faces are fanned from their first corner (a quad
0-1-2-3 becomes 0-1-2 and 0-2-3), one node and mesh per OBJ group named like the group, one
primitive per material used in the group. Faces with `vn` normals keep them (vertices shared
per position/normal pair); faces without get flat normals, each triangle its own three
vertices with the normalised cross product of its edges in winding order — what a renderer
that reads the OBJ without normals computes too.

Materials come from the MTL named by `mtllib`: a diffuse material becomes baseColorFactor =
Kd, metallic 0, roughness 1; a refracting one (illum 4, 6 or 7 with Tf) becomes a clear
dielectric: baseColorFactor = Tf, metallic 0, roughness 0, KHR_materials_transmission 1 and
KHR_materials_ior = Ni. All are double-sided.

The scene's light and camera are the Cornell box's (see the scene README): a
KHR_lights_punctual point light "light0" of intensity 3.0 on node "Light" at (0, 1.8, 0), and
a perspective camera (yfov 40°, aspect 1, znear 0.05, zfar 100) on node "Camera" at
(0, 1, 3.9) looking down -Z. With --animate, animation "slide_and_dolly" (LINEAR, 0 → 1 s)
slides node "shortBox" by (-0.15, 0, 0.10) and dollies "Camera" to (0, 1, 3.6); the script
checks that the short box stays inside the room and clear of the tall box all the way.

The buffer is embedded as a base64 data URI. Output is deterministic: same input, same bytes.
Python 3 standard library only.
"""
import argparse
import base64
import json
import math
import os
import struct
import sys
from fractions import Fraction

LIGHT_POSITION = (0.0, 1.8, 0.0)
LIGHT_INTENSITY = 3.0
CAMERA_POSITION = (0.0, 1.0, 3.9)
CAMERA_YFOV_DEG = 40.0
ANIM_END = 1.0
SHORT_BOX_SLIDE = (-0.15, 0.0, 0.10)
CAMERA_DOLLY_END = (0.0, 1.0, 3.6)


def die(msg):
    sys.exit("obj2gltf: " + msg)


def f32_bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def bits_f32(b):
    return struct.unpack("<f", struct.pack("<I", b))[0]


def f32(text):
    """The float32 nearest to the decimal `text`, ties to even (exact, no double rounding)."""
    exact = Fraction(text)
    x = bits_f32(f32_bits(float(text)))
    if Fraction(x) == exact:
        return x
    b = f32_bits(x)
    best, best_d = None, None
    for cand_bits in (b - 1, b, b + 1):
        if not 0 <= cand_bits <= 0xFFFFFFFF:
            continue
        c = bits_f32(cand_bits)
        if math.isnan(c) or math.isinf(c) or (c == 0.0 and exact != 0):
            continue
        d = abs(Fraction(c) - exact)
        if best is None or d < best_d or (d == best_d and f32_bits(c) % 2 == 0):
            best, best_d = c, d
    return best


def as_f32(x):
    """A Python float rounded to float32 (for computed values such as normals)."""
    return bits_f32(f32_bits(x))


# ------------------------------------------------------------------ OBJ / MTL


def parse_mtl(path):
    mats, cur = {}, None
    with open(path, encoding="utf-8") as f:
        for lineno, line in enumerate(f, 1):
            tok = line.split("#", 1)[0].split()
            if not tok:
                continue
            if tok[0] == "newmtl":
                cur = {"name": " ".join(tok[1:])}
                mats[cur["name"]] = cur
            elif cur is None:
                die("%s:%d: %s before newmtl" % (path, lineno, tok[0]))
            elif tok[0] in ("Kd", "Ks", "Ke", "Tf", "Ka"):
                if len(tok) != 4:
                    die("%s:%d: %s needs 3 values" % (path, lineno, tok[0]))
                cur[tok[0]] = [float(t) for t in tok[1:]]
            elif tok[0] in ("Ni", "d", "Ns", "Tr"):
                cur[tok[0]] = float(tok[1])
            elif tok[0] == "illum":
                cur["illum"] = int(tok[1])
            else:
                die("%s:%d: unsupported MTL statement %s" % (path, lineno, tok[0]))
    return mats


def parse_obj(path):
    """Returns (positions, normals, groups, mtllib): positions/normals as lists of decimal
    text triples; groups as an ordered list of [name, [[material, [face, ...]], ...]] where a
    face is a list of (position index, normal index or None), 0-based."""
    positions, normals, groups, mtllib = [], [], [], None
    group, material = None, None

    def resolve(text, count, what, lineno):
        i = int(text)
        j = i - 1 if i > 0 else count + i
        if i == 0 or not 0 <= j < count:
            die("%s:%d: %s index %d out of range (%d defined)" % (path, lineno, what, i, count))
        return j

    with open(path, encoding="utf-8") as f:
        for lineno, line in enumerate(f, 1):
            tok = line.split("#", 1)[0].split()
            if not tok:
                continue
            if tok[0] == "v":
                if len(tok) < 4:
                    die("%s:%d: v needs 3 coordinates" % (path, lineno))
                positions.append(tuple(tok[1:4]))
            elif tok[0] == "vn":
                normals.append(tuple(tok[1:4]))
            elif tok[0] in ("g", "o"):
                name = " ".join(tok[1:]) or "default"
                group = next((g for g in groups if g[0] == name), None)
                if group is None:
                    group = [name, []]
                    groups.append(group)
            elif tok[0] == "usemtl":
                material = " ".join(tok[1:])
            elif tok[0] == "mtllib":
                mtllib = " ".join(tok[1:])
            elif tok[0] == "f":
                if len(tok) < 4:
                    die("%s:%d: a face needs at least 3 corners" % (path, lineno))
                if material is None:
                    die("%s:%d: face before usemtl" % (path, lineno))
                if group is None:
                    group = ["default", []]
                    groups.append(group)
                face = []
                for corner in tok[1:]:
                    parts = corner.split("/")
                    vi = resolve(parts[0], len(positions), "vertex", lineno)
                    ni = None
                    if len(parts) == 3 and parts[2]:
                        ni = resolve(parts[2], len(normals), "normal", lineno)
                    face.append((vi, ni))
                if len({ni is None for _, ni in face}) != 1:
                    die("%s:%d: face mixes corners with and without normals" % (path, lineno))
                bucket = next((b for b in group[1] if b[0] == material), None)
                if bucket is None:
                    bucket = [material, []]
                    group[1].append(bucket)
                bucket[1].append(face)
            elif tok[0] in ("s", "vt", "l"):
                pass
            else:
                die("%s:%d: unsupported OBJ statement %s" % (path, lineno, tok[0]))
    return positions, normals, groups, mtllib


# ------------------------------------------------------------------ geometry


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def face_normal(p0, p1, p2):
    c = cross(sub(p1, p0), sub(p2, p0))
    n = math.sqrt(sum(x * x for x in c))
    if n == 0.0:
        die("degenerate triangle %r %r %r" % (p0, p1, p2))
    return tuple(as_f32(x / n) + 0.0 for x in c)  # + 0.0: no -0.0 in the file


def build_primitive(faces, positions, normals):
    """Vertices (position, normal float32 triples) and triangle indices for a face list."""
    verts, index, shared = [], [], {}
    for face in faces:
        for k in range(1, len(face) - 1):
            tri = (face[0], face[k], face[k + 1])
            if tri[0][1] is None:
                p = [tuple(f32(t) for t in positions[vi]) for vi, _ in tri]
                n = face_normal(*p)
                for q in p:
                    index.append(len(verts))
                    verts.append((q, n))
            else:
                for key in tri:
                    if key not in shared:
                        shared[key] = len(verts)
                        verts.append((tuple(f32(t) for t in positions[key[0]]),
                                      tuple(f32(t) for t in normals[key[1]])))
                    index.append(shared[key])
    return verts, index


# ------------------------------------------------------------------ animation check


def hull(points):
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - \
                    (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]) <= 0:
                out.pop()
            out.append(p)
        return out
    lower, upper = half(pts), half(reversed(pts))
    return lower[:-1] + upper[:-1]


def separated(a, b):
    """Separating-axis test for two convex polygons (lists of 2D points)."""
    for poly in (a, b):
        for i in range(len(poly)):
            e = sub(poly[(i + 1) % len(poly)], poly[i])
            axis = (-e[1], e[0])
            pa = [p[0] * axis[0] + p[1] * axis[1] for p in a]
            pb = [p[0] * axis[0] + p[1] * axis[1] for p in b]
            if max(pa) < min(pb) or max(pb) < min(pa):
                return True
    return False


def check_slide(group_points):
    """The short box's footprint swept along the slide must stay inside the room and clear
    of the tall box (both footprints are convex; the sweep of a convex shape along a segment
    is the hull of its two ends)."""
    short = [(x, z) for x, _, z in group_points["shortBox"]]
    tall = hull([(x, z) for x, _, z in group_points["tallBox"]])
    moved = [(x + SHORT_BOX_SLIDE[0], z + SHORT_BOX_SLIDE[2]) for x, z in short]
    swept = hull(short + moved)
    if not separated(swept, tall):
        die("the sliding short box would hit the tall box")
    room = [(x, z) for x, _, z in group_points["floor"]]
    xmin, xmax = max(x for x, z in room if x < 0), min(x for x, z in room if x > 0)
    zmin, zmax = max(z for x, z in room if z < 0), min(z for x, z in room if z > 0)
    for x, z in swept:
        if not (xmin < x < xmax and zmin < z < zmax):
            die("the sliding short box leaves the room at (%g, %g)" % (x, z))


# ------------------------------------------------------------------ glTF


class Writer:
    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def view(self, payload, target=None):
        while len(self.data) % 4:
            self.data.append(0)
        v = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(payload)}
        if target:
            v["target"] = target
        self.data += payload
        self.views.append(v)
        return len(self.views) - 1

    def floats(self, rows, type_, target=None, minmax=False):
        comps = len(rows[0]) if isinstance(rows[0], tuple) else 1
        flat = [x for r in rows for x in (r if comps > 1 else (r,))]
        view = self.view(struct.pack("<%df" % len(flat), *flat), target)
        acc = {"bufferView": view, "componentType": 5126, "count": len(rows), "type": type_}
        if minmax:
            cols = list(zip(*rows)) if comps > 1 else [rows]
            acc["min"] = [min(c) for c in cols]
            acc["max"] = [max(c) for c in cols]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        big = max(idx) >= 65536
        payload = struct.pack("<%d%s" % (len(idx), "I" if big else "H"), *idx)
        view = self.view(payload, 34963)
        self.accessors.append({"bufferView": view, "componentType": 5125 if big else 5123,
                               "count": len(idx), "type": "SCALAR"})
        return len(self.accessors) - 1


def material_json(name, m):
    if m is None:
        die("material %s is not in the MTL" % name)
    refract = m.get("illum") in (4, 6, 7) and "Tf" in m
    if refract:
        return {
            "name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [as_f32(x) for x in m["Tf"]] + [1.0],
                                     "metallicFactor": 0.0, "roughnessFactor": 0.0},
            "doubleSided": True,
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                           "KHR_materials_ior": {"ior": m.get("Ni", 1.5)}},
        }
    kd = m.get("Kd")
    if kd is None:
        die("material %s has no Kd" % name)
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": kd + [1.0], "metallicFactor": 0.0,
                                 "roughnessFactor": 1.0},
        "doubleSided": True,
    }


def convert(obj_path, animate):
    positions, normals, groups, mtllib = parse_obj(obj_path)
    if mtllib is None:
        die("%s names no mtllib" % obj_path)
    mtl = parse_mtl(os.path.join(os.path.dirname(obj_path), mtllib))

    w = Writer()
    materials, mat_index, meshes, nodes = [], {}, [], []
    group_points = {}
    for name, buckets in groups:
        prims = []
        for mat, faces in buckets:
            if mat not in mat_index:
                mat_index[mat] = len(materials)
                materials.append(material_json(mat, mtl.get(mat)))
            verts, idx = build_primitive(faces, positions, normals)
            group_points.setdefault(name, []).extend(v[0] for v in verts)
            prims.append({
                "attributes": {"POSITION": w.floats([v[0] for v in verts], "VEC3", 34962, True),
                               "NORMAL": w.floats([v[1] for v in verts], "VEC3", 34962)},
                "indices": w.indices(idx),
                "material": mat_index[mat],
                "mode": 4,
            })
        meshes.append({"name": name, "primitives": prims})
        nodes.append({"name": name, "mesh": len(meshes) - 1})

    light_node = len(nodes)
    nodes.append({"name": "Light", "translation": list(LIGHT_POSITION),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    camera_node = len(nodes)
    nodes.append({"name": "Camera", "translation": list(CAMERA_POSITION), "camera": 0})

    gltf = {
        "asset": {"version": "2.0", "generator": "ispm scenes/tools/obj2gltf.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"name": os.path.splitext(os.path.basename(obj_path))[0],
                    "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"name": "Camera", "type": "perspective",
                     "perspective": {"yfov": math.radians(CAMERA_YFOV_DEG), "aspectRatio": 1.0,
                                     "znear": 0.05, "zfar": 100.0}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "light0", "type": "point", "color": [1.0, 1.0, 1.0],
             "intensity": LIGHT_INTENSITY}]}},
    }
    if any("extensions" in m for m in materials):
        gltf["extensionsUsed"] += ["KHR_materials_transmission", "KHR_materials_ior"]

    if animate:
        names = [n["name"] for n in nodes]
        if "shortBox" not in names or "tallBox" not in names:
            die("--animate needs groups shortBox and tallBox")
        check_slide(group_points)
        times = w.floats([0.0, ANIM_END], "SCALAR", minmax=True)
        slide = w.floats([(0.0, 0.0, 0.0), tuple(SHORT_BOX_SLIDE)], "VEC3")
        dolly = w.floats([tuple(CAMERA_POSITION), tuple(CAMERA_DOLLY_END)], "VEC3")
        gltf["animations"] = [{
            "name": "slide_and_dolly",
            "samplers": [{"input": times, "output": slide, "interpolation": "LINEAR"},
                         {"input": times, "output": dolly, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": names.index("shortBox"), "path": "translation"}},
                         {"sampler": 1, "target": {"node": camera_node, "path": "translation"}}],
        }]
    assert nodes[light_node]["name"] == "Light"

    gltf["accessors"] = w.accessors
    gltf["bufferViews"] = w.views
    gltf["buffers"] = [{"byteLength": len(w.data),
                        "uri": "data:application/octet-stream;base64," +
                               base64.b64encode(bytes(w.data)).decode("ascii")}]
    return gltf


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("obj")
    ap.add_argument("out")
    ap.add_argument("--animate", action="store_true", help="add the slide_and_dolly animation")
    args = ap.parse_args()
    gltf = convert(args.obj, args.animate)
    text = json.dumps(gltf, indent=1, allow_nan=False) + "\n"
    tmp = args.out + ".tmp"
    with open(tmp, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    os.replace(tmp, args.out)


if __name__ == "__main__":
    main()
