#!/usr/bin/env python3
"""make_scenes.py — writes the reference renderer's analytic validation scenes (single-file
glTF 2.0, base64 buffers, deterministic bytes; Python 3 standard library only).

furnace.gltf   A closed sphere of radius 1 m centred at the origin, tessellated as a UV sphere
               of SEGMENTS x RINGS quads (vertices on the sphere, flat faces: the loader gives
               each triangle its own flat normal), uniform Lambertian albedo RHO = 0.8 on both
               sides, an isotropic point light of 1 W/sr at the centre and a 90-degree camera
               at the centre looking down -Z. Closed forms (see README.md): direct radiance
               (RHO/pi) I cos(theta)/d^2 at every point, and the area mean of the indirect
               radiance RHO^2 Phi / ((1 - RHO) pi A) for any closed enclosure (energy balance),
               A the polyhedron's area, Phi = 4 pi I.
mirror-caustic.gltf
               A square delta mirror (metallic 1, roughness 0, base colour 0.9) of 1 m x 1 m at
               y = 0, a Lambertian ceiling (albedo 0.5) of 4 m x 4 m at y = 1, a point light of
               1 W/sr at (0, 0.5, 0) and a 90-degree camera at (0, 0.2, 0) looking up. The
               caustic on the ceiling (paths light -> mirror -> ceiling -> eye) is the light of
               the mirror image of the point light at (0, -0.5, 0), scaled by the mirror's
               Schlick reflectance: E = F(cos) I cos / d^2.

Usage: make_scenes.py [OUTPUT_DIR]   (default: this script's folder)
"""
import base64
import json
import math
import os
import struct
import sys

SEGMENTS, RINGS = 128, 64
RHO = 0.8


def gltf(meshes, materials, nodes, light, camera):
    """meshes: list of (name, positions [(x,y,z)], indices [int], material index)."""
    blob = b""
    views, accessors, gmeshes = [], [], []
    for name, pos, idx, mat in meshes:
        p = b"".join(struct.pack("<3f", *v) for v in pos)
        i = b"".join(struct.pack("<I", k) for k in idx)
        lo = [min(v[c] for v in pos) for c in range(3)]
        hi = [max(v[c] for v in pos) for c in range(3)]
        # float32-rounded bounds, as the accessor's data holds them
        lo = [struct.unpack("<f", struct.pack("<f", x))[0] for x in lo]
        hi = [struct.unpack("<f", struct.pack("<f", x))[0] for x in hi]
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(p), "target": 34962})
        blob += p
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(i), "target": 34963})
        blob += i
        accessors.append({"bufferView": len(views) - 2, "componentType": 5126, "count": len(pos),
                          "type": "VEC3", "min": lo, "max": hi})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125, "count": len(idx),
                          "type": "SCALAR"})
        gmeshes.append({"name": name, "primitives": [{"attributes": {"POSITION": len(accessors) - 2},
                                                       "indices": len(accessors) - 1, "material": mat}]})
    doc = {
        "asset": {"version": "2.0", "generator": "ispm scenes/furnace/make_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [light]}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gmeshes,
        "materials": materials,
        "cameras": [camera],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def lambert(name, rho):
    return {"name": name, "doubleSided": True,
            "pbrMetallicRoughness": {"baseColorFactor": [rho, rho, rho, 1.0], "metallicFactor": 0.0,
                                     "roughnessFactor": 1.0}}


CAMERA = {"name": "Camera", "type": "perspective",
          "perspective": {"yfov": math.pi / 2, "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0}}


def furnace():
    pos = []
    for r in range(RINGS + 1):
        th = math.pi * r / RINGS
        for s in range(SEGMENTS + 1):
            ph = 2 * math.pi * s / SEGMENTS
            pos.append((math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)))
    idx = []
    for r in range(RINGS):
        for s in range(SEGMENTS):
            a, b = r * (SEGMENTS + 1) + s, r * (SEGMENTS + 1) + s + 1
            c, d = a + SEGMENTS + 1, b + SEGMENTS + 1
            if r > 0:
                idx += [a, b, c]
            if r < RINGS - 1:
                idx += [b, d, c]
    nodes = [{"name": "sphere", "mesh": 0},
             {"name": "Light", "extensions": {"KHR_lights_punctual": {"light": 0}}},
             {"name": "Camera", "camera": 0}]
    light = {"name": "light0", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 1.0}
    return gltf([("sphere", pos, idx, 0)], [lambert("wall", RHO)], nodes, light, CAMERA)


def mirror_caustic():
    def quad(y, h):
        return [(-h, y, -h), (h, y, -h), (h, y, h), (-h, y, h)], [0, 2, 1, 0, 3, 2]
    mp, mi = quad(0.0, 0.5)
    cp, ci = quad(1.0, 2.0)
    mirror = {"name": "mirror", "doubleSided": True,
              "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0,
                                       "roughnessFactor": 0.0}}
    s = math.sqrt(0.5)
    nodes = [{"name": "mirror", "mesh": 0}, {"name": "ceiling", "mesh": 1},
             {"name": "Light", "translation": [0.0, 0.5, 0.0],
              "extensions": {"KHR_lights_punctual": {"light": 0}}},
             {"name": "Camera", "translation": [0.0, 0.2, 0.0], "rotation": [s, 0.0, 0.0, s], "camera": 0}]
    light = {"name": "light0", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 1.0}
    return gltf([("mirror", mp, mi, 0), ("ceiling", cp, ci, 1)], [mirror, lambert("ceiling", 0.5)], nodes,
                light, CAMERA)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    for name, text in (("furnace.gltf", furnace()), ("mirror-caustic.gltf", mirror_caustic())):
        with open(os.path.join(out, name), "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
