#!/usr/bin/env python3
"""Writes the glTF scenes of the stability stress sequences (scenes/stress/*.gltf, docs/stability.md).

Every scene is built from axis-aligned boxes (flat normals) with Lambertian materials, under a
point or spot light (KHR_lights_punctual, radiant intensity in W/sr as the engine reads it):
  corner.gltf    a 2 m room (floor, back and left wall) and a 0.2 m cube that slides from the
                 middle of the floor into the back-left corner (003 Fig. 4: kernel bias at corners)
  spot.gltf      the same room under a spot light that pans 60 degrees about Y (every photon moves)
  thin-wall.gltf a closed box split by a 1 cm partition, point light on the left half only: photon
                 volumes wider than the partition leak light into the dark right half
  divider.gltf   a floor split by a 1.2 m wall, a point light above it; a small cube moves on the
                 left only, so nothing that changes can send light to the right half
  soft-rNNN.gltf a 0.4 m box on a 3 m floor under a spherical light of radius 0.NN m (glTF light
                 extras.ispm.radius, issue 15), 2 m up and 0.3 m to the side: the box's shadow edge
                 at x = 0.575 has a penumbra as wide as the light is large (bench/penumbra.sh)
  soft-spot-r015.gltf  the same under a spot light of radius 0.15 m pointing down
  cornell-r015.gltf    the Cornell box (../cornell-box) with its light given a radius of 0.15 m
Stdlib only; the output is committed. Run from anywhere: writes beside this file."""
import base64, json, math, os, struct

HERE = os.path.dirname(os.path.abspath(__file__))


def box(lo, hi):
    """24 vertices, 12 triangles, outward flat normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = [((1, 0, 0), [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)]),
             ((-1, 0, 0), [(x0, y0, z1), (x0, y1, z1), (x0, y1, z0), (x0, y0, z0)]),
             ((0, 1, 0), [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)]),
             ((0, -1, 0), [(x0, y0, z1), (x0, y0, z0), (x1, y0, z0), (x1, y0, z1)]),
             ((0, 0, 1), [(x1, y0, z1), (x1, y1, z1), (x0, y1, z1), (x0, y0, z1)]),
             ((0, 0, -1), [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)])]
    pos, nrm, idx = [], [], []
    for n, quad in faces:
        b = len(pos)
        pos += quad
        nrm += [n] * 4
        idx += [b, b + 1, b + 2, b, b + 2, b + 3]
    return pos, nrm, idx


class Gltf:
    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors, self.meshes, self.materials, self.nodes = [], [], [], [], []
        self.lights, self.animations, self.samplers, self.channels = [], [], [], []

    def view(self, raw, target=None):
        off = len(self.data)
        self.data.extend(raw)
        while len(self.data) % 4:
            self.data.append(0)
        v = {"buffer": 0, "byteOffset": off, "byteLength": len(raw)}
        if target:
            v["target"] = target
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, view, ctype, count, typ, lo=None, hi=None):
        a = {"bufferView": view, "componentType": ctype, "count": count, "type": typ}
        if lo is not None:
            a["min"], a["max"] = lo, hi
        self.accessors.append(a)
        return len(self.accessors) - 1

    def material(self, name, rgb):
        self.materials.append({"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1.0],
                               "metallicFactor": 0.0, "roughnessFactor": 1.0}})
        return len(self.materials) - 1

    def mesh(self, name, boxes, material):
        pos, nrm, idx = [], [], []
        for lo, hi in boxes:
            p, n, i = box(lo, hi)
            b = len(pos)
            pos += p
            nrm += n
            idx += [b + k for k in i]
        pa = self.accessor(self.view(b"".join(struct.pack("<3f", *p) for p in pos), 34962), 5126, len(pos), "VEC3",
                           [min(p[k] for p in pos) for k in range(3)], [max(p[k] for p in pos) for k in range(3)])
        na = self.accessor(self.view(b"".join(struct.pack("<3f", *n) for n in nrm), 34962), 5126, len(nrm), "VEC3")
        ia = self.accessor(self.view(b"".join(struct.pack("<I", i) for i in idx), 34963), 5125, len(idx), "SCALAR")
        self.meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pa, "NORMAL": na}, "indices": ia,
                                                          "material": material}]})
        self.nodes.append({"name": name, "mesh": len(self.meshes) - 1})
        return len(self.nodes) - 1

    def light(self, name, light, translation, rotation=None, parent=None):
        self.lights.append(light)
        n = {"name": name, "translation": translation,
             "extensions": {"KHR_lights_punctual": {"light": len(self.lights) - 1}}}
        if rotation:
            n["rotation"] = rotation
        self.nodes.append(n)
        return len(self.nodes) - 1

    def animate(self, node, path, times, values):
        comps = 4 if path == "rotation" else 3
        ta = self.accessor(self.view(struct.pack("<%df" % len(times), *times)), 5126, len(times), "SCALAR",
                           [min(times)], [max(times)])
        flat = [c for v in values for c in v]
        va = self.accessor(self.view(struct.pack("<%df" % len(flat), *flat)), 5126, len(values),
                           "VEC4" if comps == 4 else "VEC3")
        self.samplers.append({"input": ta, "output": va, "interpolation": "LINEAR"})
        self.channels.append({"sampler": len(self.samplers) - 1, "target": {"node": node, "path": path}})

    def write(self, name, roots=None):
        doc = {"asset": {"version": "2.0", "generator": "scenes/stress/make_stress.py"},
               "extensionsUsed": ["KHR_lights_punctual"],
               "extensions": {"KHR_lights_punctual": {"lights": self.lights}},
               "scene": 0, "scenes": [{"nodes": roots if roots is not None else list(range(len(self.nodes)))}],
               "nodes": self.nodes, "meshes": self.meshes, "materials": self.materials,
               "accessors": self.accessors, "bufferViews": self.views,
               "buffers": [{"byteLength": len(self.data),
                            "uri": "data:application/octet-stream;base64," + base64.b64encode(self.data).decode()}]}
        if self.channels:
            doc["animations"] = [{"name": "move", "channels": self.channels, "samplers": self.samplers}]
        with open(os.path.join(HERE, name), "w") as f:
            json.dump(doc, f, indent=1)
            f.write("\n")


def quat_y(deg):
    a = math.radians(deg) / 2
    return [0.0, math.sin(a), 0.0, math.cos(a)]


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def room(g, white, red):
    g.mesh("floor", [((-1, -0.02, -1), (1, 0, 1))], white)
    g.mesh("backWall", [((-1, 0, -1.02), (1, 2, -1))], white)
    g.mesh("leftWall", [((-1.02, 0, -1), (-1, 2, 1))], red)


# corner: the cube slides from the middle of the floor into the back-left corner, touching both walls.
g = Gltf()
white, red = g.material("white", (0.75, 0.75, 0.75)), g.material("red", (0.7, 0.15, 0.12))
cubem = g.material("cube", (0.3, 0.5, 0.75))
room(g, white, red)
cube = g.mesh("cube", [((-0.1, 0, -0.1), (0.1, 0.2, 0.1))], cubem)
g.animate(cube, "translation", [0.0, 1.0], [(0.0, 0.0, 0.0), (-0.9, 0.0, -0.9)])
g.light("Light", {"name": "light0", "type": "point", "color": [1, 1, 1], "intensity": 2.0}, [0.2, 1.6, 0.2])
g.write("corner.gltf")

# spot: the spot light, 1.6 m up, tilted 55 degrees down, pans 60 degrees about Y over 1 s.
g = Gltf()
white, red = g.material("white", (0.75, 0.75, 0.75)), g.material("red", (0.7, 0.15, 0.12))
room(g, white, red)
pivot = len(g.nodes)
g.nodes.append({"name": "Pan", "translation": [0.0, 1.6, 0.3], "children": [pivot + 1]})
t = math.radians(-55) / 2
g.light("Spot", {"name": "spot0", "type": "spot", "color": [1, 1, 1], "intensity": 6.0,
                 "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.45}}, [0.0, 0.0, 0.0],
        [math.sin(t), 0.0, 0.0, math.cos(t)])
g.animate(pivot, "rotation", [0.0, 1.0], [quat_y(30), quat_y(-30)])
g.write("spot.gltf", roots=[0, 1, 2, pivot])

# thin wall: a closed 2 m box split at x = 0 by a 1 cm partition with the light on the left.
g = Gltf()
white = g.material("white", (0.75, 0.75, 0.75))
part = g.material("partition", (0.75, 0.75, 0.75))
g.mesh("shell", [((-1, -0.02, -1), (1, 0, 1)), ((-1, 2, -1), (1, 2.02, 1)), ((-1, 0, -1.02), (1, 2, -1)),
                 ((-1.02, 0, -1), (-1, 2, 1)), ((1, 0, -1), (1.02, 2, 1))], white)
g.mesh("partition", [((-0.005, 0, -1), (0.005, 2, 1))], part)
g.light("Light", {"name": "light0", "type": "point", "color": [1, 1, 1], "intensity": 2.0}, [-0.5, 1.2, 0.0])
g.write("thin-wall.gltf")

# divider: a 1.2 m high wall splits a 3 m floor; the light is above the wall; a 0.2 m cube moves on
# the left half only.
g = Gltf()
white = g.material("white", (0.75, 0.75, 0.75))
wallm = g.material("wall", (0.6, 0.6, 0.65))
cubem = g.material("cube", (0.3, 0.5, 0.75))
g.mesh("floor", [((-1.5, -0.02, -1), (1.5, 0, 1))], white)
g.mesh("wall", [((-0.05, 0, -1), (0.05, 1.2, 1))], wallm)
cube = g.mesh("cube", [((-0.1, 0, -0.1), (0.1, 0.2, 0.1))], cubem)
g.animate(cube, "translation", [0.0, 1.0], [(-1.1, 0.0, 0.2), (-0.8, 0.0, -0.3)])
g.light("Light", {"name": "light0", "type": "point", "color": [1, 1, 1], "intensity": 3.0}, [0.0, 2.0, 0.0])
g.write("divider.gltf")

# soft shadows: one scene per light radius (the radius is part of the light); radius 0 is the
# punctual light of the same scene, the hard-shadow baseline of bench/penumbra.sh.
for radius in (0.0, 0.05, 0.15, 0.3):
    g = Gltf()
    white = g.material("white", (0.75, 0.75, 0.75))
    boxm = g.material("box", (0.6, 0.6, 0.65))
    g.mesh("floor", [((-1.5, -0.02, -1.5), (1.5, 0, 1.5))], white)
    g.mesh("box", [((0.0, 0.0, -0.2), (0.4, 0.4, 0.2))], boxm)
    g.light("Light", {"name": "sphere", "type": "point", "color": [1, 1, 1], "intensity": 6.0,
                      "extras": {"ispm": {"radius": radius}}}, [-0.3, 2.0, 0.0])
    g.write("soft-r%03d.gltf" % round(radius * 100))

# soft-spot-r015: the soft-r015 floor and box under a spot light of radius 0.15 m at the same place,
# pointing straight down (its cone reaches 0.5 rad at full intensity: the box's shadow edge is
# inside it): soft shadows through a perspective map (bench/penumbra.sh).
g = Gltf()
white = g.material("white", (0.75, 0.75, 0.75))
boxm = g.material("box", (0.6, 0.6, 0.65))
g.mesh("floor", [((-1.5, -0.02, -1.5), (1.5, 0, 1.5))], white)
g.mesh("box", [((0.0, 0.0, -0.2), (0.4, 0.4, 0.2))], boxm)
g.light("Spot", {"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": 6.0,
                 "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.7}, "extras": {"ispm": {"radius": 0.15}}},
        [-0.3, 2.0, 0.0], [-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)])
g.write("soft-spot-r015.gltf")

# cornell-r015: the Cornell box (scenes/cornell-box/cornell-box.gltf, its slide_and_dolly animation
# included) with its point light given a radius of 0.15 m: soft shadows where the boxes stand on
# the floor (bench/penumbra.sh, stress-cornell-r015; docs/shadows.md).
with open(os.path.join(HERE, "..", "cornell-box", "cornell-box.gltf")) as f:
    cornell = json.load(f)
cornell["extensions"]["KHR_lights_punctual"]["lights"][0]["extras"] = {"ispm": {"radius": 0.15}}
with open(os.path.join(HERE, "cornell-r015.gltf"), "w") as f:
    json.dump(cornell, f, indent=1)
    f.write("\n")
