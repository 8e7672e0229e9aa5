#!/usr/bin/env python3
"""Makes the textured test inputs in this folder (run once; the outputs are
committed). Needs Pillow and NumPy (pip install pillow numpy), and for the
scan ../shared/data/range/pcl/table_scene_mug_stereo_textured.ply.

- mug_scan.ply + mug_scan.png: a crop of the PCL mug stereo scan's range
  grid, every 5th cell; the lattice is its own UV chart and the scan's
  colours the texture (how RGB-D scanners export). PLY with
  `comment TextureFile mug_scan.png`.
- mug_scan.obj + mug_scan.mtl: the same scan as OBJ + MTL (map_Kd).
- parts.obj + parts.mtl + checker.png + stripes.jpg: two objects, three
  materials (one shared by both objects, a PNG and a JPEG texture).
- parts.gltf + parts.bin: a closed two-material sphere and a box placed by
  nested nodes (translation, rotation, scale), a shared material, external
  PNG and JPEG textures with samplers.
"""
import json, math, struct, sys, os
import numpy as np
from PIL import Image

here = os.path.dirname(os.path.abspath(__file__))
out = lambda n: os.path.join(here, n)

def images():
    c = np.zeros((32, 32, 3), np.uint8)
    for y in range(32):
        for x in range(32):
            c[y, x] = (230, 60, 40) if ((x // 8) + (y // 8)) % 2 else (250, 240, 220)
    Image.fromarray(c).save(out("checker.png"), optimize=True)
    s = np.zeros((32, 32, 3), np.uint8)
    for y in range(32):
        s[y, :] = (30, 90 + 4 * y, 200) if (y // 4) % 2 else (240, 200, 40)
    Image.fromarray(s).save(out("stripes.jpg"), quality=85)

def scan(src):
    with open(src, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    cols, rows = 640, 480
    nv = 209280
    vt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1"), ("g", "u1"), ("b", "u1")])
    verts = np.frombuffer(data, vt, nv, end)
    pos = end + nv * vt.itemsize
    grid = np.full(cols * rows, -1, np.int64)
    buf = memoryview(data)
    for cell in range(cols * rows):
        n = buf[pos]
        pos += 1
        if n:
            grid[cell] = struct.unpack_from("<i", data, pos)[0]
            pos += 4 * n
    grid = grid.reshape(rows, cols)
    # A crop around the mug, every 5th cell: a 40 x 34 lattice.
    r0, c0, step, R, C = 225, 305, 5, 34, 40
    sub = grid[r0:r0 + R * step:step, c0:c0 + C * step:step]
    idx = {}
    P, UV = [], []
    for r in range(R):
        for c in range(C):
            v = sub[r, c]
            if v >= 0 and np.isfinite(verts[v]["z"]):
                idx[(r, c)] = len(P)
                P.append((float(verts[v]["x"]), float(verts[v]["y"]), float(verts[v]["z"])))
                UV.append(((c + 0.5) / C, 1.0 - (r + 0.5) / R))
    # Texture: the crop's colours, 64 x 64 texels (a power of two, nearest sample).
    tex = np.zeros((64, 64, 3), np.uint8)
    for y in range(64):
        for x in range(64):
            v = grid[r0 + int((y + 0.5) / 64 * R * step), c0 + int((x + 0.5) / 64 * C * step)]
            if v >= 0:
                tex[y, x] = (verts[v]["r"], verts[v]["g"], verts[v]["b"])
    Image.fromarray(tex).save(out("mug_scan.png"), optimize=True)
    F = []
    def ok(a, b, c):
        pa, pb, pc = (np.array(P[i]) for i in (a, b, c))
        e = max(np.linalg.norm(pa - pb), np.linalg.norm(pb - pc), np.linalg.norm(pa - pc))
        return e < 0.03  # no triangle across a depth jump
    for r in range(R - 1):
        for c in range(C - 1):
            a, b, cc, d = (idx.get(k) for k in ((r, c), (r, c + 1), (r + 1, c), (r + 1, c + 1)))
            # Scanner looks down +z: (r,c)->(r+1,c)->(r,c+1) faces the camera.
            if None not in (a, b, cc) and ok(a, cc, b):
                F.append((a, cc, b))
            if None not in (b, cc, d) and ok(b, cc, d):
                F.append((b, cc, d))
    with open(out("mug_scan.ply"), "wb") as f:
        f.write((
            "ply\nformat binary_little_endian 1.0\n"
            "comment a crop of the PCL mug stereo scan (every 5th range cell); texture = its colours\n"
            "comment TextureFile mug_scan.png\n"
            f"element vertex {len(P)}\nproperty float x\nproperty float y\nproperty float z\n"
            "property float texture_u\nproperty float texture_v\n"
            f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        for p, t in zip(P, UV):
            f.write(struct.pack("<5f", *p, *t))
        for t in F:
            f.write(struct.pack("<B3i", 3, *t))
    with open(out("mug_scan.mtl"), "w") as f:
        f.write("newmtl scan\nKd 1 1 1\nillum 1\nmap_Kd mug_scan.png\n")
    with open(out("mug_scan.obj"), "w") as f:
        f.write("mtllib mug_scan.mtl\no mug_scan\n")
        for p in P:
            f.write("v %.6g %.6g %.6g\n" % p)
        for t in UV:
            f.write("vt %.6g %.6g\n" % t)
        f.write("usemtl scan\n")
        for t in F:
            f.write("f %d/%d %d/%d %d/%d\n" % tuple(i + 1 for i in t for _ in (0, 1)))
    print(f"scan: {len(P)} vertices, {len(F)} faces")

def sphere(n_lat=8, n_lon=12):
    """A closed UV sphere split at the equator: (positions, uvs, top faces, bottom faces),
    each half with its own vertices (glTF primitives do not share)."""
    halves = []
    for top in (True, False):
        P, T, F = [], [], []
        rows = range(0, n_lat // 2 + 1) if top else range(n_lat // 2, n_lat + 1)
        rid = {}
        for i in rows:
            th = math.pi * i / n_lat
            for j in range(n_lon + 1):
                # The seam column j = n_lon repeats column 0's position exactly,
                # and the poles are exact: the sphere is closed bit for bit.
                ph = 2 * math.pi * (j % n_lon) / n_lon
                rid[(i, j)] = len(P)
                snap = lambda x: 0.0 if abs(x) < 1e-9 else x
                r = snap(math.sin(th))
                P.append((snap(r * math.cos(ph)), snap(math.cos(th)), snap(-r * math.sin(ph))))
                T.append((j / n_lon, i / n_lat))  # glTF UV: origin top-left
        rl = list(rows)
        for i in rl[:-1]:
            for j in range(n_lon):
                a, b, c, d = rid[(i, j)], rid[(i, j + 1)], rid[(i + 1, j)], rid[(i + 1, j + 1)]
                if i != 0:
                    F.append((a, c, b))
                if i + 1 != n_lat:
                    F.append((b, c, d))
        halves.append((P, T, F))
    return halves

def box():
    P, T, F = [], [], []
    for axis in range(3):
        for s in (-1, 1):
            base = len(P)
            u, v = [(a) for a in range(3) if a != axis]
            for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0] * 3
                p[axis], p[u], p[v] = 0.5 * s, 0.5 * a, 0.5 * b
                P.append(tuple(p))
                T.append(((a + 1) / 2, (b + 1) / 2))
            q = (base, base + 1, base + 2, base + 3)
            tris = [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
            # Outward winding: flip when needed.
            n = [0.0] * 3
            n[axis] = s
            for t in tris:
                a, b, c = (np.array(P[i]) for i in t)
                if np.dot(np.cross(b - a, c - a), n) < 0:
                    t = (t[0], t[2], t[1])
                F.append(t)
    return P, T, F

def gltf():
    bin_ = bytearray()
    views, accs = [], []
    def add(arr, fmt, count, typ, comp, target, minmax=None):
        while len(bin_) % 4:
            bin_.append(0)
        off = len(bin_)
        for x in arr:
            bin_.extend(struct.pack(fmt, *x) if isinstance(x, tuple) else struct.pack(fmt, x))
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(bin_) - off, "target": target})
        a = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        if minmax:
            a["min"], a["max"] = minmax
        accs.append(a)
        return len(accs) - 1
    def prim(P, T, F, mat):
        mn = [min(p[i] for p in P) for i in range(3)]
        mx = [max(p[i] for p in P) for i in range(3)]
        pa = add(P, "<3f", len(P), "VEC3", 5126, 34962, (mn, mx))
        ta = add(T, "<2f", len(T), "VEC2", 5126, 34962)
        ia = add([i for f in F for i in f], "<H", 3 * len(F), "SCALAR", 5123, 34963)
        return {"attributes": {"POSITION": pa, "TEXCOORD_0": ta}, "indices": ia, "material": mat}
    (tP, tT, tF), (bP, bT, bF) = sphere()
    sphere_mesh = {"name": "ball", "primitives": [prim(tP, tT, tF, 0), prim(bP, bT, bF, 1)]}
    P, T, F = box()
    box_mesh = {"name": "crate", "primitives": [prim(P, T, F, 1)]}
    with open(out("parts.bin"), "wb") as f:
        f.write(bin_)
    doc = {
        "asset": {"version": "2.0", "generator": "lodkit test data (make.py)"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "root", "translation": [0, 1, 0], "children": [1, 2]},
            {"name": "ball_node", "mesh": 0, "rotation": [0, 0.38268343, 0, 0.92387953]},
            {"name": "crate_holder", "translation": [2.5, 0, 0], "scale": [1, 2, 1], "children": [3]},
            {"name": "crate_node", "mesh": 1, "translation": [0, 0.25, 0]},
        ],
        "meshes": [sphere_mesh, box_mesh],
        "materials": [
            {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
             "metallicFactor": 0.0, "roughnessFactor": 0.8}, "doubleSided": True},
            {"name": "stripes", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1},
             "baseColorFactor": [1, 0.9, 0.8, 1], "metallicFactor": 0.1},
             "emissiveFactor": [0.1, 0, 0], "alphaMode": "MASK", "alphaCutoff": 0.3},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 1}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071},
                     {"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 33648}],
        "images": [{"uri": "checker.png"}, {"uri": "stripes.jpg", "mimeType": "image/jpeg"}],
        "buffers": [{"uri": "parts.bin", "byteLength": len(bin_)}],
        "bufferViews": views,
        "accessors": accs,
    }
    with open(out("parts.gltf"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")

def obj():
    with open(out("parts.mtl"), "w") as f:
        f.write("# two textured materials and a plain one\n"
                "newmtl checker\nKa 0.1 0.1 0.1\nKd 1 1 1\nKs 0.2 0.2 0.2\nNs 20\nillum 2\nmap_Kd checker.png\n\n"
                "newmtl stripes\nKd 0.9 0.8 0.7\nd 0.75\nKe 0.1 0 0\nPr 0.4\nPm 0.2\nmap_Kd stripes.jpg\nmap_Ke checker.png\n\n"
                "newmtl plain\nKd 0.2 0.6 0.3\n")
    lines = ["mtllib parts.mtl"]
    P, T, F = box()
    lines.append("o crate")
    lines += ["v %g %g %g" % p for p in P]
    lines += ["vt %g %g" % t for t in T]
    lines.append("usemtl checker")
    lines += ["f %d/%d %d/%d %d/%d" % tuple(i + 1 for i in t for _ in (0, 1)) for t in F[:6]]
    lines.append("usemtl stripes")
    lines += ["f %d/%d %d/%d %d/%d" % tuple(i + 1 for i in t for _ in (0, 1)) for t in F[6:]]
    lines.append("o tile")
    lines += ["v 2 0 0", "v 3 0 0", "v 3 1 0", "v 2 1 0", "v 2 2 0", "v 3 2 0"]
    lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1", "vt 0 2", "vt 1 2"]
    lines.append("usemtl stripes")
    lines += ["f 25/25 26/26 27/27", "f 25/25 27/27 28/28"]
    lines.append("usemtl plain")
    lines += ["f 28/28 27/27 30/30", "f 28/28 30/30 29/29"]
    with open(out("parts.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")

images()
gltf()
obj()
if len(sys.argv) > 1:
    scan(sys.argv[1])
