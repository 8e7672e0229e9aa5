#!/usr/bin/env python3
"""Rate against Draco: bytes and symmetric RMS error to the original bunny
for Google Draco (through PyPI's DracoPy) and for lodkit's `.pop` stream
decoded at its full level, at 10, 12 and 14 quantisation bits.

Usage (from the repository root, after `cargo build --release -p lodkit`):

    python3 bench/draco_compare.py [--mesh data/models/stanford_bunny.ply] [--depths 6,7,8,9]

The script creates a private virtual environment (in the system temp dir)
and installs DracoPy and numpy into it with pip, then re-runs itself there.
Errors are measured by `lodkit compare --json` the same way for both (Metro:
vertex, edge and face samples both ways; symmetric RMS is the larger
direction's), against the original mesh. Draco quantises positions over the
bounding box's largest side with q bits; `.pop` over its root cube (the same
side plus 1/1024) with precision N = q. `.pop`'s octree depth R is free
(§7.2's scalable precision decouples it from N): every R of `--depths` is
tried in both coding modes, every row is printed, and the summary takes,
per q, the smallest entropy-mode `.pop` whose error is at most Draco's (or,
when none is, the most accurate one tried). `.pop`'s error is that of
`lodkit pop decode` mesh output: the full level, triangulated.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

VENV = os.path.join(tempfile.gettempdir(), "lodkit-draco-venv")


def ensure_venv():
    if os.environ.get("LODKIT_DRACO_VENV") == "1":
        return
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "-q", "DracoPy", "numpy"])
    env = dict(os.environ, LODKIT_DRACO_VENV="1")
    os.execve(py, [py] + sys.argv, env)


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
    return verts, faces


def write_obj(path, verts, faces):
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % tuple(v))
        for t in faces:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def rms(lodkit, original, other, samples):
    out = run([lodkit, "-q", "compare", original, other, "--json", "--samples", str(samples)])
    return json.loads(out)["symmetric"]["rms"]


def pop_row(args, tmp, q, depth, mode, placement="column"):
    pop = os.path.join(tmp, "pop_%d_%d_%s_%s.pop" % (q, depth, mode, placement))
    run([args.lodkit, "-q", "pop", "encode", args.mesh, "-o", pop, "--precision", str(q),
         "--depth", str(depth), "--mode", mode, "--placement", placement])
    ply = os.path.join(tmp, "pop_%d_%d_%s_%s.ply" % (q, depth, mode, placement))
    run([args.lodkit, "-q", "pop", "decode", pop, "-o", ply])
    return {"bits": q, "depth": depth, "mode": mode, "placement": placement,
            "bytes": os.path.getsize(pop), "rms": rms(args.lodkit, args.mesh, ply, args.samples)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="data/models/stanford_bunny.ply")
    ap.add_argument("--lodkit", default="target/release/lodkit")
    ap.add_argument("--bits", default="10,12,14")
    ap.add_argument("--depths", default="6,7,8,9")
    ap.add_argument("--samples", type=int, default=1_000_000)
    args = ap.parse_args()
    ensure_venv()
    import DracoPy
    import numpy as np

    tmp = tempfile.mkdtemp(prefix="lodkit-draco-")
    obj = os.path.join(tmp, "original.obj")
    run([args.lodkit, "-q", "convert", args.mesh, obj])
    verts, faces = read_obj(obj)
    pts = np.asarray(verts, dtype=np.float32)
    tris = np.asarray(faces, dtype=np.uint32)
    draco, rows = {}, []
    for q in [int(b) for b in args.bits.split(",")]:
        drc = DracoPy.encode(pts, tris, quantization_bits=q, compression_level=10)
        dec = DracoPy.decode(drc)
        dobj = os.path.join(tmp, "draco_%d.obj" % q)
        write_obj(dobj, np.asarray(dec.points).reshape(-1, 3), np.asarray(dec.faces).reshape(-1, 3))
        draco[q] = {"bytes": len(drc), "rms": rms(args.lodkit, args.mesh, dobj, args.samples)}
        for depth in [int(d) for d in args.depths.split(",")]:
            if depth > q:
                continue
            rows.append(pop_row(args, tmp, q, depth, "entropy"))
            rows.append(pop_row(args, tmp, q, depth, "entropy", "mean"))
            rows.append(pop_row(args, tmp, q, depth, "baseline", "mean"))
    print("All rows (`.pop` at full level, triangulated):\n")
    print("| bits | R | mode | placement | bytes | sym. RMS | Draco bytes | Draco sym. RMS |")
    print("|---:|---:|---|---|---:|---:|---:|---:|")
    for r in rows:
        d = draco[r["bits"]]
        print("| %d | %d | %s | %s | %d | %.3g | %d | %.3g |"
              % (r["bits"], r["depth"], r["mode"], r["placement"], r["bytes"], r["rms"], d["bytes"], d["rms"]))
    print("\nBest entropy-mode `.pop` per quantisation (smallest with RMS <= Draco's, else most accurate):\n")
    print("| bits | Draco bytes | Draco sym. RMS | .pop R | .pop bytes | .pop sym. RMS | target met |")
    print("|---:|---:|---:|---:|---:|---:|---|")
    summary = []
    for q, d in draco.items():
        cands = [r for r in rows if r["bits"] == q and r["mode"] == "entropy"]
        ok = [r for r in cands if r["rms"] <= d["rms"]]
        best = min(ok, key=lambda r: r["bytes"]) if ok else min(cands, key=lambda r: r["rms"])
        met = bool(ok) and best["bytes"] < d["bytes"]
        summary.append({"bits": q, "draco": d, "pop": best, "met": met})
        print("| %d | %d | %.3g | %d | %d | %.3g | %s |"
              % (q, d["bytes"], d["rms"], best["depth"], best["bytes"], best["rms"], "yes" if met else "no"))
    print(json.dumps({"rows": rows, "draco": draco, "summary": summary}))


if __name__ == "__main__":
    main()
