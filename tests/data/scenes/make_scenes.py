#!/usr/bin/env python3
"""Writes the small analytic test scenes of tests/test_engine.c: a 4 m x 4 m white floor
(albedo 0.8) at y = 0 lit by one spot light or one directional light. Run once; the .gltf
files are committed."""
import base64, json, struct

def floor_buffer():
    pos = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)]
    idx = [0, 2, 1, 0, 3, 2]  # counter-clockwise seen from +Y
    data = b"".join(struct.pack("<3f", *p) for p in pos) + struct.pack("<6I", *idx)
    return data

def scene(light, light_node):
    data = floor_buffer()
    return {
        "asset": {"version": "2.0", "generator": "ispm tests/data/scenes/make_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [light]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "floor", "mesh": 0}, light_node],
        "meshes": [{"name": "floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                       "metallicFactor": 0, "roughnessFactor": 1}, "doubleSided": True}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-2, 0, -2], "max": [2, 0, 2]},
            {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
    }

s = 0.7071067811865476
# Spot at (0, 2, 0) pointing straight down (−Z rotated −90° about X), cones 0.4 / 0.6 rad.
spot = scene({"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": 5.0,
              "spot": {"innerConeAngle": 0.4, "outerConeAngle": 0.6}},
             {"name": "Spot", "extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0], "rotation": [-s, 0, 0, s]})
# Directional, 2 W/m², pointing down and toward −Z: −Z rotated −60° about X → (0, −0.866, −0.5).
a = 0.5235987755982988  # half of 60° in radians
import math
sun = scene({"name": "sun", "type": "directional", "color": [1, 1, 1], "intensity": 2.0},
            {"name": "Sun", "extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 3, 0], "rotation": [-math.sin(a), 0, 0, math.cos(a)]})
for name, doc in (("floor-spot.gltf", spot), ("floor-directional.gltf", sun)):
    with open(name, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
