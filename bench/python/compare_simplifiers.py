#!/usr/bin/env python3
"""pylodkit against the CLI and against the Python simplifiers people use.

Part 1, call overhead: ``pylodkit.simplify`` on the bunny from numpy
(conversions in and out included) against the CLI's in-process time for
the same work (``lodkit simplify --json``'s ``seconds``: the simplifier
call alone, no file I/O), median of ``--repeat`` runs each.

Part 2, side by side in one run: the bunny and a 1M-triangle blob
(``pylodkit.blob``), to 10 % and 1 % of their triangles, by lodkit,
fast-simplification, pyfqmr, pymeshlab and trimesh's simplifier; wall time
of the call (numpy in, numpy out) and the symmetric Metro distance to the
input (``pylodkit.compare``, the same fixed sample count for every
result). A peer that is not installed is reported as such.

    python bench/python/compare_simplifiers.py --lodkit target/release/lodkit
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import pylodkit as lk


def overhead(lodkit_bin: str, repeat: int, ratio: float) -> dict:
    bunny = lk.bunny()
    cli = []
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "bunny.ply")
        lk.save(bunny, src)
        for _ in range(repeat if os.path.exists(lodkit_bin) else 0):
            out = subprocess.run([lodkit_bin, "simplify", src, "-o", os.path.join(d, "o.ply"),
                                  "--ratio", str(ratio), "--json"],
                                 check=True, capture_output=True, text=True).stdout
            cli.append(json.loads(out)["seconds"])
    py, inner = [], []
    lk.simplify(bunny, ratio=ratio)  # warm the page cache and the allocator
    for _ in range(repeat):
        t = time.perf_counter()
        _, r = lk.simplify(bunny, ratio=ratio)
        py.append(time.perf_counter() - t)
        inner.append(r["seconds"])
    # Without the CLI binary, the simplifier's own timing of the same call
    # (`LevelReport.seconds`, what `--json` prints) stands for it.
    c = statistics.median(cli) if cli else float("nan")
    p, i = statistics.median(py), statistics.median(inner)
    return {"ratio": ratio, "repeat": repeat, "cli_seconds": c, "python_seconds": p,
            "python_inner_seconds": i, "python_over_cli": p / c, "python_over_inner": p / i}


def peers():
    out = {}

    def lodkit_run(v, f, ratio):
        m, _ = lk.simplify(lk.Mesh(v, f), ratio=ratio)
        return m.vertices, m.faces
    out["lodkit"] = lodkit_run
    try:
        import fast_simplification

        def fs(v, f, ratio):
            return fast_simplification.simplify(v, f, target_reduction=1.0 - ratio)
        out["fast-simplification"] = fs
    except ImportError as e:
        out["fast-simplification"] = "not installed (%s)" % e
    try:
        import pyfqmr

        def fq(v, f, ratio):
            s = pyfqmr.Simplify()
            s.setMesh(v, f)
            s.simplify_mesh(target_count=int(len(f) * ratio), aggressiveness=7, preserve_border=False,
                            verbose=False)
            vv, ff, _ = s.getMesh()
            return vv, ff
        out["pyfqmr"] = fq
    except ImportError as e:
        out["pyfqmr"] = "not installed (%s)" % e
    try:
        import pymeshlab

        def ml(v, f, ratio):
            ms = pymeshlab.MeshSet()
            ms.add_mesh(pymeshlab.Mesh(v.astype(np.float64), f.astype(np.int32)))
            ms.meshing_decimation_quadric_edge_collapse(targetfacenum=int(len(f) * ratio),
                                                        preservenormal=True, optimalplacement=True)
            m = ms.current_mesh()
            return m.vertex_matrix(), m.face_matrix()
        out["pymeshlab"] = ml
    except ImportError as e:
        out["pymeshlab"] = "not installed (%s)" % e
    try:
        import trimesh

        def tm(v, f, ratio):
            m = trimesh.Trimesh(v, f, process=False)
            s = m.simplify_quadric_decimation(face_count=int(len(f) * ratio))
            return s.vertices, s.faces
        out["trimesh"] = tm
    except ImportError as e:
        out["trimesh"] = "not installed (%s)" % e
    return out


def side_by_side(big: int, samples: int, ratios) -> list:
    meshes = [("bunny", lk.bunny()), ("blob %dk" % (big // 1000), lk.blob(big))]
    rows = []
    tools = peers()
    for mname, mesh in meshes:
        v64 = mesh.vertices.astype(np.float64)
        f64 = mesh.faces.astype(np.int64)
        f32 = mesh.faces.astype(np.int32)
        for ratio in ratios:
            for tname, fn in tools.items():
                row = {"mesh": mname, "input_triangles": mesh.n_faces, "ratio": ratio, "tool": tname}
                if isinstance(fn, str):
                    row["note"] = fn
                    rows.append(row)
                    continue
                # Each peer gets the dtypes it takes without converting.
                v, f = (mesh.vertices, mesh.faces) if tname == "lodkit" else (
                    (v64, f32) if tname in ("fast-simplification", "pymeshlab") else (v64, f64))
                try:
                    t = time.perf_counter()
                    ov, of = fn(v, f, ratio)
                    row["seconds"] = time.perf_counter() - t
                    out = lk.Mesh(np.asarray(ov, np.float64), np.asarray(of, np.int64))
                    row["triangles"] = out.n_faces
                    r = lk.compare(mesh, out, samples=samples)
                    row["mean_pct"] = r["symmetric"]["mean_pct"]
                    row["max_pct"] = r["symmetric"]["max_pct"]
                except Exception as e:
                    row["note"] = "failed: %s" % str(e).splitlines()[0][:120]
                rows.append(row)
                print(json.dumps(row), file=sys.stderr, flush=True)
    return rows


def table(rows) -> str:
    out = ["| mesh | target | tool | triangles | time (s) | mean error (% diag) | max error (% diag) |",
           "|---|---|---|---:|---:|---:|---:|"]
    for r in rows:
        if "seconds" not in r:
            out.append("| %s | %g %% | %s | — | — | — | %s |" % (r["mesh"], r["ratio"] * 100, r["tool"], r.get("note", "")))
            continue
        out.append("| %s | %g %% | %s | %d | %.3f | %.4f | %.4f |" % (
            r["mesh"], r["ratio"] * 100, r["tool"], r["triangles"], r["seconds"], r["mean_pct"], r["max_pct"]))
    return "\n".join(out)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--lodkit", default="target/release/lodkit", help="the lodkit CLI binary")
    p.add_argument("--repeat", type=int, default=15)
    p.add_argument("--big", type=int, default=1_000_000, help="triangles of the blob")
    p.add_argument("--samples", type=int, default=1_000_000, help="compare samples per kind")
    p.add_argument("--skip-overhead", action="store_true")
    p.add_argument("--skip-peers", action="store_true")
    a = p.parse_args()
    print("machine: %s, %d cores, Python %s; load before: %s" % (
        platform.processor() or platform.machine(), os.cpu_count(), platform.python_version(),
        " ".join("%.2f" % x for x in os.getloadavg())))
    if not a.skip_overhead:
        o = overhead(a.lodkit, a.repeat, 0.1)
        print("overhead (bunny, ratio 0.1, median of %d): CLI --json %.4f s, Python call %.4f s "
              "(its simplifier alone %.4f s): Python / CLI = %.3f, Python / simplifier = %.3f" % (
                  o["repeat"], o["cli_seconds"], o["python_seconds"], o["python_inner_seconds"],
                  o["python_over_cli"], o["python_over_inner"]))
    if not a.skip_peers:
        rows = side_by_side(a.big, a.samples, (0.1, 0.01))
        print(table(rows))
    print("load after: %s" % " ".join("%.2f" % x for x in os.getloadavg()))


if __name__ == "__main__":
    main()
