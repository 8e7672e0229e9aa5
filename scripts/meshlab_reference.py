#!/usr/bin/env python3
"""MeshLab reference values for lodkit's Metro-style `compare`.

Rerun (from the repository root):

    pip install pymeshlab==2025.7.post1
    python3 scripts/meshlab_reference.py

What it does:

1. loads data/models/stanford_bunny.ply (the full bunny, 69,451 faces);
2. simplifies it with MeshLab's quadric edge-collapse decimation to 5,000
   faces and saves data/reference/stanford_bunny_simplified.ply (binary
   little-endian PLY; pymeshlab 2025.7 writes double-precision coordinates);
3. reloads both files from disk (so MeshLab measures exactly what lodkit
   loads), removes the full bunny's 1,113 unreferenced vertices (lodkit never
   samples them; MeshLab samples every vertex), and runs MeshLab's Hausdorff
   Distance filter in both directions with vertex, edge and face sampling and
   the per-kind sample count lodkit's default uses:
   N = max(10 x faces of the larger mesh, 1,000,000);
4. writes data/reference/meshlab_hausdorff.json with the figures, the
   pymeshlab version, the exact parameters and this command.

MeshLab's face sampling is Monte Carlo with its own RNG, so the figures are
one draw; lodkit's test allows 2% on mean/RMS and 5% on max.
"""

import hashlib
import json
import os
import platform
import sys
from importlib.metadata import version

import pymeshlab

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
ORIGINAL = "data/models/stanford_bunny.ply"
SIMPLIFIED = "data/reference/stanford_bunny_simplified.ply"
OUTPUT = "data/reference/meshlab_hausdorff.json"

# lodkit's defaults (crates/mesh/src/metrics/mod.rs).
DEFAULT_SAMPLES_PER_FACE = 10
DEFAULT_MIN_SAMPLES = 1_000_000

DECIMATION = {
    "targetfacenum": 5000,
    "qualitythr": 0.3,
    "preserveboundary": False,
    "preservenormal": False,
    "preservetopology": False,
    "optimalplacement": True,
    "planarquadric": False,
    "autoclean": True,
}

# Only the coordinates and the faces go into the file.
SAVE = {
    "binary": True,
    "save_vertex_normal": False,
    "save_vertex_color": False,
    "save_vertex_quality": False,
    "save_vertex_flag": False,
    "save_vertex_radius": False,
    "save_face_color": False,
    "save_face_quality": False,
    "save_face_flag": False,
    "save_wedge_color": False,
    "save_wedge_texcoord": False,
    "save_wedge_normal": False,
    "save_textures": False,
}

# No sample is dropped: MeshLab ignores samples farther than `maxdist`, and
# 100% of the diagonal is far beyond any distance between these meshes.
MAXDIST_PERCENT = 100.0


def path(rel):
    return os.path.join(ROOT, rel)


def sha256(rel):
    with open(path(rel), "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def mesh_info(ms, index, rel):
    m = ms.mesh(index)
    return {
        "path": rel,
        "sha256": sha256(rel),
        "vertices": m.vertex_number(),
        "faces": m.face_number(),
        "bbox_diagonal": m.bounding_box().diagonal(),
    }


def hausdorff(ms, sampled, target, samplenum):
    params = {
        "sampledmesh": sampled,
        "targetmesh": target,
        "savesample": False,
        "samplevert": True,
        "sampleedge": True,
        "samplefauxedge": False,
        "sampleface": True,
        "samplenum": samplenum,
        "maxdist": pymeshlab.PercentageValue(MAXDIST_PERCENT),
    }
    out = ms.get_hausdorff_distance(**params)
    return {k: (float(v) if isinstance(v, float) else v) for k, v in out.items()}


def main():
    os.makedirs(path("data/reference"), exist_ok=True)

    # (1) + (2): simplify and save.
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path(ORIGINAL))
    ms.meshing_decimation_quadric_edge_collapse(**DECIMATION)
    ms.save_current_mesh(path(SIMPLIFIED), **SAVE)

    # (3): measure the files as saved.
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path(ORIGINAL))  # mesh 0: as loaded (with unreferenced vertices)
    ms.load_new_mesh(path(SIMPLIFIED))  # mesh 1
    ms.load_new_mesh(path(ORIGINAL))  # mesh 2: unreferenced vertices removed
    ms.meshing_remove_unreferenced_vertices()
    orig, simp, orig_clean = 0, 1, 2

    faces_a = ms.mesh(orig_clean).face_number()
    faces_b = ms.mesh(simp).face_number()
    n = max(DEFAULT_SAMPLES_PER_FACE * max(faces_a, faces_b), DEFAULT_MIN_SAMPLES)

    a_to_b = hausdorff(ms, orig_clean, simp, n)
    b_to_a = hausdorff(ms, simp, orig_clean, n)
    a_to_b_unref = hausdorff(ms, orig, simp, n)

    result = {
        "generator": "scripts/meshlab_reference.py",
        "command": "python3 scripts/meshlab_reference.py",
        "rerun": "pip install pymeshlab==%s && python3 scripts/meshlab_reference.py"
        % version("pymeshlab"),
        "pymeshlab_version": version("pymeshlab"),
        "python_version": platform.python_version(),
        "platform": platform.platform(),
        "original": mesh_info(ms, orig, ORIGINAL),
        "original_referenced_vertices": ms.mesh(orig_clean).vertex_number(),
        "simplified": mesh_info(ms, simp, SIMPLIFIED),
        "decimation": {
            "filter": "meshing_decimation_quadric_edge_collapse",
            "params": DECIMATION,
            "save_params": SAVE,
        },
        "hausdorff": {
            "filter": "get_hausdorff_distance",
            "samplenum": n,
            "samplenum_rule": "max(10 * faces of the larger mesh, 1000000): lodkit's default",
            "params": {
                "savesample": False,
                "samplevert": True,
                "sampleedge": True,
                "samplefauxedge": False,
                "sampleface": True,
                "samplenum": n,
                "maxdist": "PercentageValue(%g)" % MAXDIST_PERCENT,
            },
            "preprocessing": "meshing_remove_unreferenced_vertices on the original "
            "(lodkit never samples unreferenced vertices)",
            "units": "min/max/mean/RMS in model units; diag_mesh_0 is the sampled "
            "mesh's bbox diagonal, diag_mesh_1 the target's",
            # lodkit's a_to_b with A = original, B = simplified.
            "original_to_simplified": a_to_b,
            "simplified_to_original": b_to_a,
        },
        "hausdorff_with_unreferenced_vertices": {
            "note": "the original as loaded: MeshLab samples its 1,113 unreferenced "
            "vertices too, which inflates the maximum; for information only",
            "original_to_simplified": a_to_b_unref,
        },
    }
    with open(path(OUTPUT), "w") as f:
        json.dump(result, f, indent=2, sort_keys=True)
        f.write("\n")
    json.dump(result["hausdorff"], sys.stdout, indent=2, sort_keys=True)
    print()


if __name__ == "__main__":
    main()
