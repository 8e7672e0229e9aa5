#!/usr/bin/env python3
"""Texture-space error of a simplified textured mesh against its input.

usage: texerr.py INPUT.obj OUTPUT.obj [samples]

Both are OBJ + MTL with one base colour texture (map_Kd). Samples points
uniformly by area on OUTPUT; for each, the closest point of INPUT's
surface (exact point-triangle distance over the 16 triangles with the
nearest centroids). Reports, as JSON:
- uv_texels_mean / uv_texels_p95: |uv_out - uv_in| in texels of the
  input's texture (how far the texture slid on the surface);
- color_rmse: RMS of the RGB difference (0..255) between OUTPUT's texture
  at uv_out and INPUT's texture at uv_in (what a viewer sees change).
Needs numpy and Pillow. Deterministic (fixed seed).
"""
import json, os, sys
import numpy as np
from PIL import Image

def load_obj(path):
    V, T, F, FT, tex = [], [], [], [], None
    d = os.path.dirname(path)
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            V.append([float(x) for x in w[1:4]])
        elif w[0] == "vt":
            T.append([float(x) for x in w[1:3]])
        elif w[0] == "f":
            c = [x.split("/") for x in w[1:]]
            vi = [int(x[0]) for x in c]
            ti = [int(x[1]) if len(x) > 1 and x[1] else 0 for x in c]
            for k in range(1, len(c) - 1):
                F.append([vi[0], vi[k], vi[k + 1]])
                FT.append([ti[0], ti[k], ti[k + 1]])
        elif w[0] == "mtllib":
            for l in open(os.path.join(d, line.split(None, 1)[1].strip())):
                m = l.split()
                if m and m[0] == "map_Kd" and tex is None:
                    tex = os.path.join(d, m[-1])
    V, T = np.array(V, float), np.array(T, float)
    fix = lambda idx, n: np.where(idx < 0, idx + n, idx - 1)
    F = fix(np.array(F), len(V))
    FT = fix(np.array(FT), len(T))
    img = np.asarray(Image.open(tex).convert("RGB"), float)
    return V, T, F, FT, img

def sample_tex(img, uv):
    h, w, _ = img.shape
    x = np.clip(np.mod(uv[:, 0], 1.0) * w - 0.5, 0, w - 1)
    y = np.clip((1.0 - np.mod(uv[:, 1], 1.0)) * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    return (img[y0, x0] * (1 - fx) * (1 - fy) + img[y0, x1] * fx * (1 - fy)
            + img[y1, x0] * (1 - fx) * fy + img[y1, x1] * fx * fy)

def closest_bary(p, a, b, c):
    """Barycentrics of the closest point on triangles (a,b,c) to p (Ericson)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    den = np.where(np.abs(va + vb + vc) > 1e-30, va + vb + vc, 1e-30)
    v, w = vb / den, vc / den
    bary = np.stack([1 - v - w, v, w], -1)
    def put(mask, u, v_, w_):
        bary[mask] = np.stack([u, v_, w_], -1)[mask]
    one, zero = np.ones_like(d1), np.zeros_like(d1)
    t = d1 / np.where(d1 - d3 != 0, d1 - d3, 1e-30)
    put((vc <= 0) & (d1 >= 0) & (d3 <= 0), 1 - t, t, zero)
    t = d2 / np.where(d2 - d6 != 0, d2 - d6, 1e-30)
    put((vb <= 0) & (d2 >= 0) & (d6 <= 0), 1 - t, zero, t)
    t = (d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1e-30)
    put((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), zero, 1 - t, t)
    put((d1 <= 0) & (d2 <= 0), one, zero, zero)
    put((d3 >= 0) & (d4 <= d3), zero, one, zero)
    put((d6 >= 0) & (d5 <= d6), zero, zero, one)
    return bary

def main():
    inp, out = sys.argv[1], sys.argv[2]
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 20000
    V0, T0, F0, FT0, img0 = load_obj(inp)
    V1, T1, F1, FT1, img1 = load_obj(out)
    rng = np.random.default_rng(1)
    tri = V1[F1]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    f = rng.choice(len(F1), n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bc = np.stack([1 - s, s * (1 - r2), s * r2], -1)
    P = (tri[f] * bc[:, :, None]).sum(1)
    uv1 = (T1[FT1[f]] * bc[:, :, None]).sum(1)
    A, B, C = V0[F0[:, 0]], V0[F0[:, 1]], V0[F0[:, 2]]
    cen = (A + B + C) / 3
    K = min(16, len(F0))
    uv0 = np.zeros((n, 2))
    for lo in range(0, n, 512):
        p = P[lo:lo + 512]
        d = ((p[:, None, :] - cen[None]) ** 2).sum(-1)
        cand = np.argpartition(d, K - 1, axis=1)[:, :K]
        pp = np.repeat(p[:, None, :], K, 1)
        bary = closest_bary(pp, A[cand], B[cand], C[cand])
        q = bary[..., 0:1] * A[cand] + bary[..., 1:2] * B[cand] + bary[..., 2:3] * C[cand]
        best = ((q - pp) ** 2).sum(-1).argmin(1)
        rows = np.arange(len(p))
        t = cand[rows, best]
        bb = bary[rows, best]
        uv0[lo:lo + 512] = (T0[FT0[t]] * bb[:, :, None]).sum(1)
    h, w, _ = img0.shape
    texels = np.linalg.norm((uv1 - uv0) * [w, h], axis=1)
    col = sample_tex(img1, uv1) - sample_tex(img0, uv0)
    print(json.dumps({
        "uv_texels_mean": float(texels.mean()),
        "uv_texels_p95": float(np.percentile(texels, 95)),
        "color_rmse": float(np.sqrt((col ** 2).mean())),
        "faces": int(len(F1)),
    }))

main()
