#!/usr/bin/env python3
"""Rate against Draco: bytes and symmetric RMS error to the original bunny
for Google Draco (through PyPI's DracoPy) and for lodkit's `.pop` stream
decoded at its full level, at 10, 12 and 14 quantisation bits.

Usage (from the repository root, after `cargo build --release -p lodkit`):

    python3 bench/draco_compare.py [--mesh data/models/stanford_bunny.ply]

The script creates a private virtual environment (in the system temp dir)
and installs DracoPy and numpy into it with pip, then re-runs itself there.
Errors are measured by `lodkit compare --json` (Metro: vertex, edge and face
samples both ways; symmetric RMS is the larger direction's). Draco quantises
positions over the bounding box's largest side with q bits, `.pop` over its
root cube (the same side plus 1/1024) with precision N = q; the octree depth
R is `.pop`'s automatic choice, clamped to at most q.
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="data/models/stanford_bunny.ply")
    ap.add_argument("--lodkit", default="target/release/lodkit")
    ap.add_argument("--bits", default="10,12,14")
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
    rows = []
    for q in [int(b) for b in args.bits.split(",")]:
        drc = DracoPy.encode(pts, tris, quantization_bits=q, compression_level=10)
        dec = DracoPy.decode(drc)
        dobj = os.path.join(tmp, "draco_%d.obj" % q)
        write_obj(dobj, np.asarray(dec.points).reshape(-1, 3), np.asarray(dec.faces).reshape(-1, 3))
        row = {"bits": q, "draco_bytes": len(drc), "draco_rms": rms(args.lodkit, args.mesh, dobj, args.samples)}
        for mode in ["entropy", "baseline"]:
            pop = os.path.join(tmp, "bunny_%d_%s.pop" % (q, mode))
            run([args.lodkit, "-q", "pop", "encode", args.mesh, "-o", pop, "--precision", str(q), "--mode", mode])
            ply = os.path.join(tmp, "pop_%d_%s.ply" % (q, mode))
            run([args.lodkit, "-q", "pop", "decode", pop, "-o", ply])
            row["pop_%s_bytes" % mode] = os.path.getsize(pop)
            row["pop_%s_rms" % mode] = rms(args.lodkit, args.mesh, ply, args.samples)
        rows.append(row)
    print("| bits | Draco bytes | Draco sym. RMS | .pop entropy bytes | .pop baseline bytes | .pop sym. RMS |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(
            "| %d | %d | %.3g | %d | %d | %.3g |"
            % (
                r["bits"],
                r["draco_bytes"],
                r["draco_rms"],
                r["pop_entropy_bytes"],
                r["pop_baseline_bytes"],
                r["pop_entropy_rms"],
            )
        )
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
