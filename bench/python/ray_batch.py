#!/usr/bin/env python3
"""The Ray batch's throughput, 1 worker against 2, and its failure and resume.

Generates ``--assets`` blobs (``pylodkit.blob``, ``--triangles`` each,
seeds 1..N) as PLY files, runs ``pylodkit.batch.run_batch`` over them with
1 worker and then with 2 (a fresh local Ray cluster and a fresh output
folder each; the default LOD chain, each level measured), and prints the
assets per second of each (``wall_seconds``: first task submitted to last
result; the cluster's start is reported apart). Then adds a broken asset
and reruns the 2-worker batch over the same output: the complete assets
are skipped, the broken one is reported with its message.

    python bench/python/ray_batch.py --assets 40
"""
from __future__ import annotations

import argparse
import os
import shutil
import tempfile

import pylodkit as lk
from pylodkit.batch import run_batch


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--assets", type=int, default=40)
    p.add_argument("--triangles", type=int, default=40_000)
    p.add_argument("--dir", help="work folder (default: a temporary one, removed after)")
    a = p.parse_args()
    work = a.dir or tempfile.mkdtemp(prefix="lodkit-ray-")
    src = os.path.join(work, "assets")
    os.makedirs(src, exist_ok=True)
    for i in range(a.assets):
        path = os.path.join(src, "blob%02d.ply" % i)
        if not os.path.exists(path):
            lk.save(lk.blob(a.triangles, seed=i + 1), path)
    print("load before: %s" % " ".join("%.2f" % x for x in os.getloadavg()))
    result = {}
    for workers in (1, 2):
        out = os.path.join(work, "out%d" % workers)
        shutil.rmtree(out, ignore_errors=True)
        s = run_batch(src, out, workers=workers, quiet=True)
        assert s["failed"] == 0, s
        result[workers] = s
        print("%d worker(s): %d assets in %.2f s = %.2f assets/s (Ray start %.1f s); load %s" % (
            workers, len(s["assets"]), s["wall_seconds"], len(s["assets"]) / s["wall_seconds"],
            s["ray_init_seconds"], " ".join("%.2f" % x for x in os.getloadavg())))
    speedup = result[1]["wall_seconds"] / result[2]["wall_seconds"]
    print("2 workers / 1 worker throughput: %.2fx" % speedup)

    with open(os.path.join(src, "zz_broken.ply"), "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nend_header\n\x00")
    s = run_batch(src, os.path.join(work, "out2"), workers=2, quiet=True)
    print("rerun with a broken asset added: %d made, %d skipped (complete), %d failed in %.2f s" % (
        s["ok"], s["skipped"], s["failed"], s["wall_seconds"]))
    for r in s["assets"]:
        if r["status"] == "failed":
            print("  failed %s: %s" % (r["asset"], r["error"]))
    print("summary: %s" % os.path.join(work, "out2", "summary.md"))
    print("load after: %s" % " ".join("%.2f" % x for x in os.getloadavg()))
    if not a.dir:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
