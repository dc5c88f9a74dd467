#!/usr/bin/env python3
"""Writes scenes/atrium/: a small Sponza-like atrium (issue 17 item 8), textured and animated.

A court 12 m x 5 m open to the sky, between two arcades of five round arches on six columns
(z = +-2.5; spring line 2.4 m, arch radius 0.78 m, walls 0.3 m thick with arch soffits), aisles
2 m deep behind them under a flat roof at 4 m, upper walls to 7 m over the arcades, end walls at
x = +-6. Modelled as coarsely as the light transport allows: flat walls are single quads, the
columns 12-sided, arches 12 segments, the ball 16 x 10: 1,442 triangles.

Materials (metallic-roughness, all double-sided): a marble tile floor (baseColor and
metallicRoughness textures: polished tiles, rough grout), sandstone blocks on the walls and
columns (baseColor), a plaster aisle roof, three woven curtains (one fabric texture tinted red,
green and blue by baseColorFactor) hung in arches of the north arcade where the sun falls, and a
stone ball with brass bands (baseColor and metallicRoughness: the bands are metal, roughness
0.35, above the mirror threshold so no specular eye pass runs).

Lights (KHR_lights_punctual): the sun, directional, from the south-west over the south upper wall
onto the north arcade, its curtains and the floor in front of them (irradiance 3 W/m^2), and a
warm lantern, a point light of 1.2 W/sr, on the node "Lantern" flying a loop through the court.
Animations: "roll" (the ball rolls 4 m along the court and back, 8 s: translation and the
matching rotation about z) and "lantern" (the loop, 8 s); both LINEAR, 17 keys.

Textures are procedural PNGs written here (zlib + struct, 8-bit RGB, filter type 1 on every row),
so the output is reproduced byte for byte: tests/e2e_atrium.sh runs this script into a temporary
folder and compares every file. Stdlib only.
usage: make_atrium.py [OUT_DIR]   (default: scenes/atrium next to this folder)"""
import json, math, os, struct, sys, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "atrium")

# --- dimensions (metres) ---------------------------------------------------------------------
XW = 6.0            # end walls at x = +-XW
ZC = 2.5            # arcade planes at z = +-ZC
ZO = 4.5            # outer aisle walls at z = +-ZO
HALF_T = 0.15       # half the arcade wall's thickness
COLS = [-5.0, -3.0, -1.0, 1.0, 3.0, 5.0]
COL_R = 0.22        # column radius
SPRING = 2.4        # arch spring line (top of the capitals)
ARCH_R = 1.0 - COL_R
ROOF = 4.0          # aisle roof, top of the arcade walls
TOP = 7.0           # top of the upper walls
SEG_COL, SEG_ARCH = 12, 12
CURTAINS = [("red", -3.0, (0.80, 0.06, 0.05)), ("green", 1.0, (0.06, 0.55, 0.10)),
            ("blue", 3.0, (0.06, 0.12, 0.70))]   # material, bay's left column (north arcade), tint
KEYS = 17            # animation keys over 8 s (every 0.5 s)
DURATION = 8.0

# --- PNG ---------------------------------------------------------------------------------------
def png(w, h, pixel):
    """8-bit RGB PNG bytes; pixel(x, y) -> (r, g, b) in 0..255. Filter 1 (Sub) on every row."""
    raw = bytearray()
    for y in range(h):
        raw.append(1)
        prev = (0, 0, 0)
        for x in range(w):
            p = pixel(x, y)
            raw.extend(((p[0] - prev[0]) & 255, (p[1] - prev[1]) & 255, (p[2] - prev[2]) & 255))
            prev = p
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))

def hash2(a, b, seed):
    """Deterministic integer hash -> [0, 1)."""
    h = (a * 374761393 + b * 668265263 + seed * 2246822519) & 0xffffffff
    h = ((h ^ (h >> 13)) * 1274126177) & 0xffffffff
    return ((h ^ (h >> 16)) & 0xffff) / 65536.0

def vnoise(x, y, cell, seed, period):
    """Smooth value noise (period cells wide, so the texture tiles)."""
    fx, fy = x / cell, y / cell
    ix, iy = int(math.floor(fx)), int(math.floor(fy))
    tx, ty = fx - ix, fy - iy
    tx, ty = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
    v = [hash2((ix + i) % period, (iy + j) % period, seed) for j in (0, 1) for i in (0, 1)]
    return (v[0] * (1 - tx) + v[1] * tx) * (1 - ty) + (v[2] * (1 - tx) + v[3] * tx) * ty

def clamp8(v):
    return max(0, min(255, int(round(v))))

# Floor: 4 x 4 marble tiles per 256-texel repeat (0.75 m tiles), alternating light and grey-green
# veined stone, 3-texel grout. Neutral grey on average, so colour bleeding shows as a tint.
def floor_px(x, y):
    tx, ty = x // 64, y // 64
    if x % 64 < 3 or y % 64 < 3:
        return (92, 90, 86)
    light = (tx + ty) % 2 == 0
    n = vnoise(x, y, 16, 7, 16) * 0.6 + vnoise(x, y, 8, 9, 32) * 0.4
    vein = abs(math.sin((x * 0.7 + y * 0.4) / 9.0 + 6.0 * n))
    base = (212, 210, 204) if light else (120, 124, 122)
    k = 0.88 + 0.12 * vein + 0.05 * (hash2(tx, ty, 3) - 0.5)
    return tuple(clamp8(c * k) for c in base)

def floor_mr_px(x, y):
    # G roughness, B metallic: polished tiles 0.35, grout 0.95; no metal.
    if x % 64 < 3 or y % 64 < 3:
        return (0, 242, 0)
    return (0, clamp8(90 + 30 * vnoise(x, y, 16, 11, 16)), 0)

# Sandstone: 4 courses of 2 blocks per 128-texel repeat (1 m x 0.25 m blocks, the courses offset
# by half a block), warm and a little uneven, 2-texel mortar.
def stone_px(x, y):
    course = y // 32
    xs = (x + (32 if course % 2 else 0)) % 128
    if y % 32 < 2 or xs % 64 < 2:
        return (150, 140, 122)
    block = xs // 64 + 2 * course
    k = 0.9 + 0.1 * hash2(block, course, 5) + 0.08 * (vnoise(x, y, 8, 13, 16) - 0.5)
    return (clamp8(196 * k), clamp8(172 * k), clamp8(136 * k))

# Fabric: a near-white twill (diagonal ribs), tinted by each curtain's baseColorFactor.
def fabric_px(x, y):
    rib = 0.90 + 0.10 * (((x + y) // 2) % 2)
    k = rib * (0.94 + 0.06 * vnoise(x, y, 8, 17, 8))
    return (clamp8(250 * k),) * 3

# Ball: 64 x 32 (u around, v pole to pole): light limestone with three brass bands.
def band(y):
    return any(abs(y - c) <= 1 for c in (9, 16, 23))

def ball_px(x, y):
    if band(y):
        return (225, 180, 95)
    k = 0.92 + 0.08 * vnoise(x, y, 8, 19, 8)
    return (clamp8(220 * k), clamp8(214 * k), clamp8(200 * k))

def ball_mr_px(x, y):
    return (0, 89, 255) if band(y) else (0, 204, 0)   # bands: metal, roughness 0.35; stone 0.8

TEXTURES = [  # file, size, pixel function
    ("floor_basecolor.png", 256, 256, floor_px),
    ("floor_metallic_roughness.png", 256, 256, floor_mr_px),
    ("stone_basecolor.png", 128, 128, stone_px),
    ("fabric_basecolor.png", 32, 32, fabric_px),
    ("ball_basecolor.png", 64, 32, ball_px),
    ("ball_metallic_roughness.png", 64, 32, ball_mr_px),
]

# --- geometry --------------------------------------------------------------------------------
def f32(v):
    return struct.unpack("<f", struct.pack("<f", v))[0]

class Mesh:
    def __init__(self, name, material):
        self.name, self.material = name, material
        self.pos, self.nrm, self.uv, self.idx = [], [], [], []

    def vert(self, p, n, uv):
        self.pos.append(tuple(f32(c) for c in p))
        self.nrm.append(n)
        self.uv.append(uv)
        return len(self.pos) - 1

    def poly(self, pts, n, uvf):
        """A convex planar polygon (fan), normal n, texcoords uvf(point)."""
        base = [self.vert(p, n, uvf(p)) for p in pts]
        for i in range(1, len(base) - 1):
            self.idx += [base[0], base[i], base[i + 1]]

def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def unit(a):
    n = math.sqrt(sum(c * c for c in a))
    return tuple(c / n for c in a)

def normal_of(pts):
    return unit(cross(sub(pts[1], pts[0]), sub(pts[2], pts[0])))

def planar_uv(scale):
    """Texcoords by projecting onto the polygon's dominant plane, scale metres per repeat."""
    def make(n):
        ax = max(range(3), key=lambda k: abs(n[k]))
        u, v = {0: (2, 1), 1: (0, 2), 2: (0, 1)}[ax]
        return lambda p: (p[u] / scale, -p[v] / scale)
    return make

def quad(m, pts, scale):
    n = normal_of(pts)
    m.poly(pts, n, planar_uv(scale)(n))

def box(m, lo, hi, scale):
    """Axis-aligned box without its bottom face, normals outward."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    quad(m, [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)], scale)
    quad(m, [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], scale)
    quad(m, [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)], scale)
    quad(m, [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)], scale)
    quad(m, [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], scale)

STONE_M = 2.0     # metres per sandstone texture repeat (1 m blocks)
FLOOR_M = 3.0     # metres per floor repeat (0.75 m tiles)

floor = Mesh("floor", "marble")
floor.poly([(-XW, 0, -ZO), (-XW, 0, ZO), (XW, 0, ZO), (XW, 0, -ZO)], (0.0, 1.0, 0.0),
           lambda p: (p[0] / FLOOR_M, p[2] / FLOOR_M))

walls = Mesh("walls", "sandstone")
for s in (-1, 1):
    # Outer aisle walls and the upper walls over the arcades, facing the inside.
    quad(walls, [(-XW, 0, s * ZO), (XW, 0, s * ZO), (XW, ROOF, s * ZO), (-XW, ROOF, s * ZO)][::s], STONE_M)
    quad(walls, [(-XW, ROOF, s * ZC), (XW, ROOF, s * ZC), (XW, TOP, s * ZC), (-XW, TOP, s * ZC)][::s], STONE_M)
    # End walls: full height over the court, roof height over the aisles.
    ends = [(s * XW, 0, -ZO), (s * XW, 0, ZO), (s * XW, ROOF, ZO), (s * XW, ROOF, -ZO)]
    quad(walls, ends if s > 0 else ends[::-1], STONE_M)
    up = [(s * XW, ROOF, -ZC), (s * XW, ROOF, ZC), (s * XW, TOP, ZC), (s * XW, TOP, -ZC)]
    quad(walls, up if s > 0 else up[::-1], STONE_M)

def arch_points(xc, z):
    return [(xc - ARCH_R * math.cos(math.pi * i / SEG_ARCH), SPRING + ARCH_R * math.sin(math.pi * i / SEG_ARCH), z)
            for i in range(SEG_ARCH + 1)]

for s in (-1, 1):
    for zf in (s * ZC - HALF_T, s * ZC + HALF_T):
        n = (0.0, 0.0, -1.0) if zf < s * ZC else (0.0, 0.0, 1.0)
        uvf = planar_uv(STONE_M)(n)
        # Solid wall from the end walls to the first and last columns.
        for xa, xb in ((-XW, COLS[0]), (COLS[-1], XW)):
            walls.poly([(xa, 0, zf), (xb, 0, zf), (xb, ROOF, zf), (xa, ROOF, zf)], n, uvf)
        # The spandrels over each arch: fans from the bay's top corners.
        for xa, xb in zip(COLS, COLS[1:]):
            arc = arch_points((xa + xb) / 2, zf)
            half = SEG_ARCH // 2
            walls.poly([(xa, ROOF, zf), (xa, SPRING, zf)] + arc[:half + 1], n, uvf)
            walls.poly([(xb, ROOF, zf)] + arc[half:] + [(xb, SPRING, zf)], n, uvf)
            walls.poly([(xa, ROOF, zf), arc[half], (xb, ROOF, zf)], n, uvf)
    # Arch soffits: the underside of each arch, facing down and inward.
    for xa, xb in zip(COLS, COLS[1:]):
        xc = (xa + xb) / 2
        for i in range(SEG_ARCH):
            a0, a1 = math.pi * i / SEG_ARCH, math.pi * (i + 1) / SEG_ARCH
            am = (a0 + a1) / 2
            n = (math.cos(am), -math.sin(am), 0.0)
            p = [(xc - ARCH_R * math.cos(a), SPRING + ARCH_R * math.sin(a)) for a in (a0, a1)]
            zs = (s * ZC - HALF_T, s * ZC + HALF_T)
            pts = [(p[0][0], p[0][1], zs[0]), (p[0][0], p[0][1], zs[1]), (p[1][0], p[1][1], zs[1]),
                   (p[1][0], p[1][1], zs[0])]
            walls.poly(pts, n, lambda q, i=i: (i / SEG_ARCH * 2.0, (q[2] - zs[0]) / STONE_M))

roof = Mesh("roof", "plaster")
for s in (-1, 1):
    pts = [(-XW, ROOF, s * (ZC - HALF_T)), (XW, ROOF, s * (ZC - HALF_T)), (XW, ROOF, s * ZO), (-XW, ROOF, s * ZO)]
    roof.poly(pts if s < 0 else pts[::-1], (0.0, -1.0, 0.0), planar_uv(STONE_M)((0.0, 1.0, 0.0)))

columns = Mesh("columns", "sandstone")
for s in (-1, 1):
    for xc in COLS:
        zc = s * ZC
        box(columns, (xc - 0.3, 0.0, zc - 0.3), (xc + 0.3, 0.3, zc + 0.3), STONE_M)
        box(columns, (xc - 0.3, SPRING - 0.2, zc - 0.3), (xc + 0.3, SPRING, zc + 0.3), STONE_M)
        for i in range(SEG_COL):
            a0, a1 = 2 * math.pi * i / SEG_COL, 2 * math.pi * (i + 1) / SEG_COL
            ring = []
            for a, y in ((a0, 0.3), (a1, 0.3), (a1, SPRING - 0.2), (a0, SPRING - 0.2)):
                ring.append((xc + COL_R * math.cos(a), y, zc + COL_R * math.sin(a)))
            base = []
            for p, a in zip(ring, (a0, a1, a1, a0)):
                base.append(columns.vert(p, (math.cos(a), 0.0, math.sin(a)), (a / (2 * math.pi), -p[1] / STONE_M)))
            columns.idx += [base[0], base[2], base[1], base[0], base[3], base[2]]

curtain_meshes = []
for name, xa, _ in CURTAINS:
    m = Mesh("curtain_" + name, "curtain_" + name)
    x0, x1, y0, y1 = xa + 0.32, xa + 2.0 - 0.32, 0.35, 2.95
    z = ZC - HALF_T - 0.08          # in front of the north arcade, court side
    folds = 8
    pts = []
    for i in range(folds + 1):
        x = x0 + (x1 - x0) * i / folds
        pts.append((x, z - (0.07 if i % 2 else 0.0)))
    for i in range(folds):
        (xa_, za), (xb_, zb) = pts[i], pts[i + 1]
        n = unit((-(zb - za), 0.0, xb_ - xa_))
        n = n if n[2] < 0 else (-n[0], 0.0, -n[2])  # toward the court
        quadpts = [(xa_, y0, za), (xb_, y0, zb), (xb_, y1, zb), (xa_, y1, za)]
        m.poly(quadpts, n, lambda p: ((p[0] - x0) / 0.5, -(p[1] - y0) / 0.5))
    curtain_meshes.append(m)

ball = Mesh("ball", "ball")
BALL_R, SU, SV = 0.4, 16, 10
grid = []
for j in range(SV + 1):
    th = math.pi * j / SV
    row = []
    for i in range(SU + 1):
        ph = 2 * math.pi * i / SU
        n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
        row.append(ball.vert(tuple(BALL_R * c for c in n), n, (i / SU, j / SV)))
    grid.append(row)
for j in range(SV):
    for i in range(SU):
        a, b, c, d = grid[j][i], grid[j][i + 1], grid[j + 1][i + 1], grid[j + 1][i]
        if j > 0:
            ball.idx += [a, b, c]
        if j < SV - 1:
            ball.idx += [a, c, d]

MESHES = [floor, walls, roof, columns] + curtain_meshes + [ball]

# --- buffer ----------------------------------------------------------------------------------
data = bytearray()
views, accessors = [], []

def view(blob, target=None):
    while len(data) % 4:
        data.append(0)
    v = {"buffer": 0, "byteOffset": len(data), "byteLength": len(blob)}
    if target:
        v["target"] = target
    data.extend(blob)
    views.append(v)
    return len(views) - 1

def accessor(blob, comp, count, kind, target=None, lohi=None):
    a = {"bufferView": view(blob, target), "componentType": comp, "count": count, "type": kind}
    if lohi:
        a["min"], a["max"] = lohi
    accessors.append(a)
    return len(accessors) - 1

def rounded(v):
    return [round(c, 6) for c in v]

MATERIALS = ["marble", "sandstone", "plaster"] + ["curtain_" + c[0] for c in CURTAINS] + ["ball"]
gl_meshes = []
for m in MESHES:
    lo = [min(p[k] for p in m.pos) for k in range(3)]
    hi = [max(p[k] for p in m.pos) for k in range(3)]
    pa = accessor(b"".join(struct.pack("<3f", *p) for p in m.pos), 5126, len(m.pos), "VEC3", 34962, (lo, hi))
    na = accessor(b"".join(struct.pack("<3f", *n) for n in m.nrm), 5126, len(m.nrm), "VEC3", 34962)
    ta = accessor(b"".join(struct.pack("<2f", *t) for t in m.uv), 5126, len(m.uv), "VEC2", 34962)
    ia = accessor(b"".join(struct.pack("<H", i) for i in m.idx), 5123, len(m.idx), "SCALAR", 34963)
    gl_meshes.append({"name": m.name, "primitives": [{"attributes": {"POSITION": pa, "NORMAL": na, "TEXCOORD_0": ta},
                                                      "indices": ia, "material": MATERIALS.index(m.material)}]})

# Animations: keys every 0.5 s over 8 s.
times = [DURATION * k / (KEYS - 1) for k in range(KEYS)]
time_acc = accessor(b"".join(struct.pack("<f", t) for t in times), 5126, len(times), "SCALAR",
                    lohi=([times[0]], [times[-1]]))

def ball_x(t):
    return -2.0 + 4.0 * (1.0 - math.cos(2 * math.pi * t / DURATION)) / 2.0   # -2 -> 2 -> -2

ball_t = [(ball_x(t), BALL_R, -0.6) for t in times]
ball_r = []
for t in times:
    ang = -(ball_x(t) + 2.0) / BALL_R          # rolling along +x turns it about -z
    ball_r.append((0.0, 0.0, math.sin(ang / 2), math.cos(ang / 2)))
lantern_t = [(3.5 * math.sin(2 * math.pi * t / DURATION), 2.2 + 0.4 * math.sin(4 * math.pi * t / DURATION),
              1.2 * math.cos(2 * math.pi * t / DURATION)) for t in times]
bt = accessor(b"".join(struct.pack("<3f", *v) for v in ball_t), 5126, len(times), "VEC3")
br = accessor(b"".join(struct.pack("<4f", *v) for v in ball_r), 5126, len(times), "VEC4")
lt = accessor(b"".join(struct.pack("<3f", *v) for v in lantern_t), 5126, len(times), "VEC3")

# --- document --------------------------------------------------------------------------------
def texinfo(i):
    return {"index": i}

nodes = [{"name": m.name, "mesh": k} for k, m in enumerate(MESHES)]
BALL_NODE = len(MESHES) - 1
nodes[BALL_NODE]["translation"] = rounded(ball_t[0])
LANTERN_NODE = len(nodes)
nodes.append({"name": "Lantern", "translation": rounded(lantern_t[0]), "extensions": {"KHR_lights_punctual": {"light": 1}}})
# The sun: directional, shining down the node's -Z; aimed along (0.3, -1, 0.55) normalised.
sun_dir = unit((0.3, -1.0, 0.55))
f = (0.0, 0.0, -1.0)
c = cross(f, sun_dir)
q = unit((c[0], c[1], c[2], 1.0 + sum(a * b for a, b in zip(f, sun_dir))))
nodes.append({"name": "Sun", "rotation": rounded(q), "extensions": {"KHR_lights_punctual": {"light": 0}}})
# Camera: at the west end of the court, eye height 1.7 m, looking east and 8 degrees up.
pitch = math.radians(8.0) / 2
yaw = math.radians(-90.0) / 2                      # -Z -> +X
qy = (0.0, math.sin(yaw), 0.0, math.cos(yaw))
qx = (math.sin(pitch), 0.0, 0.0, math.cos(pitch))
qc = (qy[3] * qx[0] + qy[0] * qx[3] + qy[1] * qx[2] - qy[2] * qx[1],
      qy[3] * qx[1] - qy[0] * qx[2] + qy[1] * qx[3] + qy[2] * qx[0],
      qy[3] * qx[2] + qy[0] * qx[1] - qy[1] * qx[0] + qy[2] * qx[3],
      qy[3] * qx[3] - qy[0] * qx[0] - qy[1] * qx[1] - qy[2] * qx[2])
nodes.append({"name": "Camera", "camera": 0, "translation": [-5.6, 1.7, 0.0], "rotation": rounded(qc)})

images = [{"uri": t[0]} for t in TEXTURES]
textures = [{"source": k, "sampler": 0} for k in range(len(TEXTURES))]
def pbr(base, rough, metal=0.0, base_tex=None, mr_tex=None):
    p = {"baseColorFactor": list(base) + [1.0], "metallicFactor": metal, "roughnessFactor": rough}
    if base_tex is not None:
        p["baseColorTexture"] = texinfo(base_tex)
    if mr_tex is not None:
        p["metallicRoughnessTexture"] = texinfo(mr_tex)
    return p

materials = [
    {"name": "marble", "pbrMetallicRoughness": pbr((1.0, 1.0, 1.0), 1.0, 0.0, 0, 1), "doubleSided": True},
    {"name": "sandstone", "pbrMetallicRoughness": pbr((1.0, 1.0, 1.0), 0.9, 0.0, 2), "doubleSided": True},
    {"name": "plaster", "pbrMetallicRoughness": pbr((0.78, 0.76, 0.72), 0.9), "doubleSided": True},
] + [{"name": "curtain_" + n, "pbrMetallicRoughness": pbr(tint, 1.0, 0.0, 3), "doubleSided": True}
     for n, _, tint in CURTAINS] + [
    {"name": "ball", "pbrMetallicRoughness": pbr((1.0, 1.0, 1.0), 1.0, 1.0, 4, 5), "doubleSided": True},
]

doc = {
    "asset": {"version": "2.0", "generator": "ispm scenes/tools/make_atrium.py"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "sun", "type": "directional", "color": [1.0, 0.96, 0.88], "intensity": 3.0},
        {"name": "lantern", "type": "point", "color": [1.0, 0.8, 0.55], "intensity": 1.2}]}},
    "scene": 0,
    "scenes": [{"name": "atrium", "nodes": list(range(len(nodes)))}],
    "nodes": nodes,
    "cameras": [{"name": "Camera", "type": "perspective",
                 "perspective": {"yfov": math.radians(60.0), "aspectRatio": 4.0 / 3.0, "znear": 0.05, "zfar": 100.0}}],
    "meshes": gl_meshes,
    "materials": materials,
    "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
    "images": images,
    "textures": textures,
    "animations": [
        {"name": "roll", "channels": [{"sampler": 0, "target": {"node": BALL_NODE, "path": "translation"}},
                                      {"sampler": 1, "target": {"node": BALL_NODE, "path": "rotation"}}],
         "samplers": [{"input": time_acc, "output": bt, "interpolation": "LINEAR"},
                      {"input": time_acc, "output": br, "interpolation": "LINEAR"}]},
        {"name": "lantern", "channels": [{"sampler": 0, "target": {"node": LANTERN_NODE, "path": "translation"}}],
         "samplers": [{"input": time_acc, "output": lt, "interpolation": "LINEAR"}]},
    ],
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(data), "uri": "atrium.bin"}],
}

os.makedirs(OUT, exist_ok=True)
with open(os.path.join(OUT, "atrium.bin"), "wb") as fo:
    fo.write(bytes(data))
for name, w, h, fn in TEXTURES:
    with open(os.path.join(OUT, name), "wb") as fo:
        fo.write(png(w, h, fn))
with open(os.path.join(OUT, "atrium.gltf"), "w") as fo:
    json.dump(doc, fo, indent=1)
    fo.write("\n")
print("make_atrium.py: %d triangles, %d bytes of geometry, %d textures" %
      (sum(len(m.idx) // 3 for m in MESHES), len(data), len(TEXTURES)), file=sys.stderr)
