#!/usr/bin/env python3
"""lodkit's conformance suite: every real scan through every path, every
output read back by every reader that claims it.

Inputs: the shipped bunny, plus every real scan of ``../shared/data`` (one
line says so when that folder is absent). Each input goes through
``build``, ``mco build``, ``pop encode``, ``lods``, ``convert`` (to every
format that can hold it) and ``render``; each output is then

- read back by the CLI (``info``, ``mco info``/``extract``, ``pop stats``/
  ``decode``), by ``pylodkit`` (when importable) and, for ``.mco``/``.pop``,
  by the wasm decoders under Node (the viewer's worker code), whose cuts
  must match the native library's bit for bit (``native digest``);
- at the input's detail: a stream's finest level (particles) and an
  octree's full cut (vertices) hold between half and twice the input's
  samples (vertices of a mesh, points of a cloud, valid cells of a range
  image), and for meshes their mean distance to the input (``compare``)
  within one of the input's edge lengths;
- keeping its attributes where the format holds them (colours in → colours
  out; UVs through OBJ/GLB/PLY);
- crack-free on closed inputs: every cut by budget (20 of them), by LOD
  number and by view (6 cameras, 2 tolerances) has no boundary edge (an
  edge one triangle uses), so no hole and no T-junction seam; holes (loops
  of area over 1e-8 × diagonal²) are counted apart in the table;
- byte-identical when run again; a cut-short ``.mco`` still serves cuts.

Usage: run.py --lodkit BIN --native BIN --wasm FILE [--data DIR] [--work DIR]
              [--only NAME[,NAME]] [--jobs N]
Exit 0 when every check passed; the last line reads 'N passed, N failed'.
A check may be marked a known gap (printed as KNOWN GAP, listed before
the failures, failing nothing); none is at present.
"""
from __future__ import annotations

import argparse
import base64
import concurrent.futures as cf
import hashlib
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

try:  # the second reader; the suite still runs the others without it
    import pylodkit  # type: ignore
except ImportError:  # pragma: no cover
    pylodkit = None
try:
    from PIL import Image  # type: ignore
except ImportError:  # pragma: no cover
    Image = None


@dataclass
class Case:
    """One input and what it is."""

    name: str
    path: Path
    kind: str  # mesh | points | range | scans
    closed: bool = False
    colors: bool = False
    uvs: bool = False
    extra: list = field(default_factory=list)  # more files (scan sets)


def cases(data: Path | None) -> list[Case]:
    out = [Case("bunny_shipped", ROOT / "data/models/stanford_bunny.ply", "mesh")]
    if data is None:
        return out
    m, p, r, t = data / "meshes", data / "points", data / "range", data / "textured"
    out += [
        Case("bunny_closed", m / "stanford_bunny_closed_glmark2.ply", "mesh", closed=True),
        Case("armadillo_closed", m / "stanford_armadillo_cgal26k.ply", "mesh", closed=True),
        Case("bunny_res4_dirty", m / "stanford_bunny_res4.ply", "mesh"),
        Case("mug_gridmesh", m / "table_scene_mug_stereo_textured_gridmesh.ply", "mesh", colors=True),
        Case("mug_textured", t / "table_scene_mug_rgbd.obj", "mesh", uvs=True),
        Case("lms400_cloud", p / "table_scene_lms400.ply", "points"),
        # Airborne LiDAR (LAZ, feet, projected CRS): colours 16-bit in 8-bit range.
        Case("autzen_laz", p / "autzen_trim.laz", "points", colors=True),
        Case("mug_range", r / "pcl/table_scene_mug_stereo_textured.ply", "range", colors=True),
        Case("bunny_scans", r / "stanford_bunny/bun.conf", "scans"),
    ]
    return [c for c in out if c.path.exists()]


class Suite:
    def __init__(self, args):
        self.bin = args.lodkit
        self.native = args.native
        self.wasm = args.wasm
        self.work = Path(args.work)
        self.lock = threading.Lock()
        self.passed = 0
        self.failed: list[str] = []
        self.table: list[str] = []
        self.bounds: dict[str, float] = {}
        self.gaps: list[str] = []

    # --- bookkeeping -------------------------------------------------------
    def check(self, case: str, what: str, ok: bool, detail: str = "", gap: bool = False) -> bool:
        """Counts one check; a failed `gap` check is a known gap, printed
        and listed apart (it fails nothing)."""
        with self.lock:
            if ok:
                self.passed += 1
            elif gap:
                line = f"KNOWN GAP {case}: {what}" + (f" ({detail})" if detail else "")
                self.gaps.append(line)
                print(line, flush=True)
            else:
                line = f"FAIL {case}: {what}" + (f" ({detail})" if detail else "")
                self.failed.append(line)
                print(line, flush=True)
        return ok

    def row(self, line: str) -> None:
        with self.lock:
            self.table.append(line)

    # --- running things ----------------------------------------------------
    def lodkit(self, *args, timeout=900) -> subprocess.CompletedProcess:
        return subprocess.run(
            [self.bin, *map(str, args)], capture_output=True, text=True, timeout=timeout
        )

    def run_ok(self, case: str, what: str, *args, timeout=900):
        t = time.monotonic()
        r = self.lodkit(*args, timeout=timeout)
        detail = (r.stderr.strip().splitlines() or [""])[-1][:300]
        self.check(case, f"{what} exits 0", r.returncode == 0, f"exit {r.returncode}: {detail}")
        return r if r.returncode == 0 else None, time.monotonic() - t

    def info(self, path: Path) -> dict | None:
        r = self.lodkit("info", path, "--json")
        if r.returncode != 0:
            return None
        try:
            return json.loads(r.stdout)
        except json.JSONDecodeError:
            return None

    def error_pct(self, case: Case, out: Path) -> float | None:
        """Symmetric mean distance between the input and `out`, in % of the
        input's diagonal (`lodkit compare`); meshes only."""
        if case.kind != "mesh":
            return None
        r = self.lodkit("compare", case.path, out, "--samples", "100000", "--json")
        if r.returncode != 0:
            self.check(case.name, f"compare reads {out.name}", False, r.stderr.strip()[:200])
            return None
        return json.loads(r.stdout)["symmetric"]["mean_pct"]

    def error_bound(self, case: Case) -> float:
        """The mean error (% of the diagonal) a product at the input's
        detail may have: the input's typical edge length (from its area and
        face count, as for equilateral triangles), at least 0.1 %."""
        return self.bounds.get(case.name, 0.5)

    # --- readers -----------------------------------------------------------
    def read_mesh_file(self, case: str, path: Path, want: dict) -> dict | None:
        """CLI and pylodkit read a mesh/cloud file; counts agree; attributes kept."""
        rel = path.name
        got = self.info(path)
        if not self.check(case, f"lodkit info reads {rel}", got is not None):
            return None
        count = got.get("faces", got.get("points", 0))
        self.check(case, f"{rel} is not empty", count > 0, json.dumps(got)[:200])
        attrs = set(got.get("attributes", []))
        for a in want.get("attributes", ()):
            self.check(case, f"{rel} keeps {a}", a in attrs, f"has {sorted(attrs)}")
        if pylodkit is not None:
            try:
                g = pylodkit.load(str(path))
                n = g.n_faces if hasattr(g, "n_faces") else len(g)
                ok = n == count
                self.check(case, f"pylodkit reads {rel} with the CLI's count", ok, f"{n} vs {count}")
            except Exception as e:  # noqa: BLE001 - any failure is the finding
                self.check(case, f"pylodkit reads {rel}", False, str(e)[:200])
        return got

    def read_mco(self, case: Case, path: Path, samples: int, partner: Path | None = None) -> None:
        name = f"{path.parent.name}/{path.name}"
        r = self.lodkit("mco", "info", path, "--json")
        if not self.check(case.name, f"lodkit mco info reads {name}", r.returncode == 0, r.stderr.strip()[:300]):
            return
        r2 = self.lodkit("info", path)
        self.check(case.name, f"lodkit info describes {name}", r2.returncode == 0, r2.stderr.strip()[:200])
        # The full-resolution cut, through the CLI.
        full = self.work / case.name / f"{path.stem}_full.ply"
        r = self.lodkit("mco", "extract", path, "--triangles", "4000000000", "-o", full)
        if not self.check(case.name, f"mco extract reads {name}", r.returncode == 0, r.stderr.strip()[:300]):
            return
        got = self.info(full) or {}
        verts, tris = got.get("vertices", 0), got.get("faces", 0)
        err = self.error_pct(case, full)
        err_s = f", mean error {err:.3f} % of the diagonal" if err is not None else ""
        self.row(f"| {case.name} | {name} | octree full cut | {tris:,} triangles, {verts:,} vertices{err_s} | input {samples:,} samples |")
        if err is not None:
            b = self.error_bound(case)
            self.check(case.name, f"{name}: full cut's mean error within one input edge ({b:.2f} % of the diagonal)", err <= b, f"{err:.3f} %")
        if samples:
            self.check(
                case.name,
                f"{name}: full cut at the input's detail (vertices within 2x of {samples} samples)",
                samples / 2 <= verts <= samples * 2,
                f"{verts} vertices",
            )
        if case.colors:
            self.check(case.name, f"{name}: colours kept", "colors" in got.get("attributes", []), str(got.get("attributes")))
        budgets = [b for b in (500, 2000, 20000) if b <= max(tris, 1)] or [max(tris, 1)]
        # pylodkit
        py_counts = None
        if pylodkit is not None:
            try:
                m = pylodkit.mco.load(str(path))
                py_counts = [m.extract(triangles=b).n_faces for b in budgets]
                self.check(case.name, f"pylodkit reads {name}", m.full_triangles == tris, f"{m.full_triangles} vs {tris}")
            except Exception as e:  # noqa: BLE001
                self.check(case.name, f"pylodkit reads {name}", False, str(e)[:200])
        # wasm, against the native library's digests
        if self.wasm:
            res = wasm_read(self.wasm, [{"file": str(path), "budgets": budgets}])
            w = res[0] if res else {"ok": False, "error": "no output"}
            if self.check(case.name, f"wasm reads {name}", w.get("ok"), w.get("error", "")[:200]):
                self.check(case.name, f"wasm full triangles of {name}", w["full_triangles"] == tris, f"{w['full_triangles']} vs {tris}")
                if case.colors:
                    self.check(case.name, f"wasm sees colours in {name}", w["colors"])
                for cut in w["cuts"]:
                    nd = native_digest(self.native, partner, 0, path, cut["budget"]) if partner else None
                    if nd is not None:
                        ok = nd["mco"]["digest"] == cut["digest"] and nd["mco"]["triangles"] == cut["triangles"]
                        self.check(case.name, f"wasm cut of {name} at {cut['budget']} equals the native one", ok,
                                   f"{cut} vs {nd['mco']}")
                if py_counts is not None:
                    wc = [c["triangles"] for c in w["cuts"]]
                    self.check(case.name, f"pylodkit and wasm cut {name} alike", py_counts == wc, f"{py_counts} vs {wc}")
        if case.closed:
            self.cracks(case, path, tris, got)

    def prefix(self, case: Case, path: Path) -> None:
        """A cut-short `.mco` serves the LOD numbers its whole chunks hold."""
        data = path.read_bytes()
        cut = path.with_name(path.stem + "_prefix.mco")
        cut.write_bytes(data[: len(data) * 6 // 10])
        r = self.lodkit("mco", "info", cut)
        self.check(case.name, "mco info reads a cut-short .mco (60 % of it)", r.returncode == 0, r.stderr.strip()[:200])
        out = cut.with_suffix(".ply")
        r = self.lodkit("mco", "extract", cut, "--triangles", "1000", "-o", out)
        self.check(case.name, "mco extract cuts a cut-short .mco", r.returncode == 0, r.stderr.strip()[:200])

    def cracks(self, case: Case, path: Path, full_tris: int, full_info: dict) -> None:
        """No boundary edge in any cut of a closed input's octree."""
        name = path.name
        full = self.work / case.name / f"{path.stem}_full.ply"
        holes, _, edges = open_loops(full, full_info.get("bbox", {}).get("diagonal", 1.0))
        self.check(case.name, f"{name}: full cut closed", edges == 0,
                   f"{edges} boundary edges, {holes} open loops")
        tmp = self.work / case.name / "cuts"
        tmp.mkdir(parents=True, exist_ok=True)
        worst = []
        lo, hi = 100, max(full_tris, 200)
        budgets = sorted({int(round(lo * (hi / lo) ** (i / 19))) for i in range(20)})
        cuts = [("--triangles", str(b)) for b in budgets]
        cuts += [("--lod", str(k)) for k in (1, 10, 100, 1000)]
        bb = full_info.get("bbox", {})
        if bb:
            c = [(a + b) / 2 for a, b in zip(bb["min"], bb["max"])]
            d = bb["diagonal"]
            dirs = [(1, 0.2, 0), (-1, 0.2, 0), (0, 1, 0.1), (0, -1, 0.1), (0.3, 0.2, 1), (0.3, 0.2, -1)]
            for dist in (0.8, 2.5):
                for dx, dy, dz in dirs:
                    n = math.sqrt(dx * dx + dy * dy + dz * dz)
                    eye = [c[0] + dx / n * d * dist, c[1] + dy / n * d * dist, c[2] + dz / n * d * dist]
                    for tol in ("1", "4"):
                        cuts.append(("--view", ",".join(f"{v:.6g}" for v in eye), "--look-at",
                                     ",".join(f"{v:.6g}" for v in c), "--tolerance", tol))
        diag = full_info.get("bbox", {}).get("diagonal", 1.0)
        holes_total = seams_total = edges_total = 0
        for i, cut in enumerate(cuts):
            out = tmp / f"cut{i}.ply"
            r = self.lodkit("mco", "extract", path, *cut, "-o", out)
            if not self.check(case.name, f"{name} cut {' '.join(cut)}", r.returncode == 0, r.stderr.strip()[:200]):
                continue
            holes, seams, edges = open_loops(out, diag)
            holes_total += holes
            seams_total += seams
            edges_total += edges
            if edges:
                worst.append(f"{' '.join(cut[:2])}: {edges} boundary edges, {holes} open loops")
        self.check(case.name, f"{name}: {len(cuts)} cuts crack-free (no boundary edge)",
                   not worst, "; ".join(worst[:6]))
        self.row(f"| {case.name} | {name} | crack check | {len(cuts)} cuts: {edges_total} boundary edges, "
                 f"{holes_total} open loops, {seams_total} seams of no area | |")
        shutil.rmtree(tmp, ignore_errors=True)

    def read_pop(self, case: Case, path: Path, samples: int, partner: Path | None = None) -> None:
        name = f"{path.parent.name}/{path.name}"
        r = self.lodkit("pop", "stats", path, "--json")
        if not self.check(case.name, f"lodkit pop stats reads {name}", r.returncode == 0, r.stderr.strip()[:300]):
            return
        st = json.loads(r.stdout)
        levels = st.get("levels", [])
        finest = sum(lv.get("new_particles", 0) for lv in levels) if levels else st.get("particles", 0)
        finest = st.get("particles", finest)
        tris = levels[-1].get("triangles", 0) if levels else 0
        self.row(f"| {case.name} | {name} | stream finest level (depth {st.get('depth')}) | {finest:,} particles, {tris:,} triangles | input {samples:,} samples |")
        if samples:
            self.check(case.name, f"{name}: finest level at the input's detail (particles within 2x of {samples})",
                       samples / 2 <= finest <= samples * 2, f"{finest} particles")
        r2 = self.lodkit("info", path)
        self.check(case.name, f"lodkit info describes {name}", r2.returncode == 0, r2.stderr.strip()[:200])
        dec = self.work / case.name / f"{path.stem}_finest.ply"
        r = self.lodkit("pop", "decode", path, "-o", dec)
        if self.check(case.name, f"lodkit pop decode reads {name}", r.returncode == 0, r.stderr.strip()[:300]):
            got = self.info(dec) or {}
            self.check(case.name, f"{name}: decoded level has triangles", got.get("faces", 0) > 0)
            err = self.error_pct(case, dec)
            if err is not None:
                self.row(f"| {case.name} | {name} | stream finest level error | mean {err:.3f} % of the diagonal | |")
                b = self.error_bound(case)
                self.check(case.name, f"{name}: finest level's mean error within one input edge ({b:.2f} % of the diagonal)", err <= b, f"{err:.3f} %")
            if case.colors:
                self.check(case.name, f"{name}: colours kept", "colors" in got.get("attributes", []), str(got.get("attributes")))
        py_tris = None
        if pylodkit is not None:
            try:
                mesh = pylodkit.pop.decode(path.read_bytes())
                py_tris = mesh.n_faces
                self.check(case.name, f"pylodkit decodes {name}", py_tris > 0 and py_tris == tris, f"{py_tris} vs {tris}")
            except Exception as e:  # noqa: BLE001
                self.check(case.name, f"pylodkit decodes {name}", False, str(e)[:200])
        if self.wasm:
            res = wasm_read(self.wasm, [{"file": str(path)}])
            w = res[0] if res else {"ok": False, "error": "no output"}
            if self.check(case.name, f"wasm decodes {name}", w.get("ok"), w.get("error", "")[:200]):
                self.check(case.name, f"wasm finest level of {name} has the CLI's triangles", w["triangles"] == tris,
                           f"{w['triangles']} vs {tris}")
                nd = native_digest(self.native, path, w["level"], partner, 1000) if partner else None
                if nd is not None:
                    self.check(case.name, f"wasm level of {name} equals the native one", nd["pop"]["digest"] == w["digest"],
                               f"{w['digest']} vs {nd['pop']['digest']}")

    def read_pictures(self, case: str, html: Path) -> None:
        """Every PNG embedded in report.html shows something."""
        if Image is None:
            return
        text = html.read_text()
        pngs = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", text)
        self.check(case, "report.html has pictures", len(pngs) > 0)
        blank = 0
        for b64 in pngs:
            if shown_fraction(Image.open(io.BytesIO(base64.b64decode(b64)))) < 0.005:
                blank += 1
        self.check(case, f"every picture of report.html shows the model ({len(pngs)} pictures)", blank == 0, f"{blank} blank")

    # --- the paths ---------------------------------------------------------
    def run_case(self, case: Case) -> None:
        d = self.work / case.name
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir(parents=True)
        src = case.path
        inf = self.info(src) if case.kind != "scans" else {}
        samples = 0
        if inf:
            samples = inf.get("vertices") or inf.get("points") or 0
            if inf.get("kind") == "mesh":
                samples = inf["vertices"] - inf.get("unreferenced_vertices", 0)
                if inf.get("faces") and inf.get("area") and inf["bbox"]["diagonal"] > 0:
                    edge = math.sqrt(4 * inf["area"] / (math.sqrt(3) * inf["faces"]))
                    with self.lock:
                        self.bounds[case.name] = max(0.1, 100 * edge / inf["bbox"]["diagonal"])
        self.check(case.name, "lodkit info reads the input", inf is not None)
        print(f"-- {case.name}: {src.name} ({case.kind}, {samples:,} samples)", flush=True)

        # build
        t = time.monotonic()
        r, secs = self.run_ok(case.name, "build", "-q", "build", src, "--out", d / "build")
        if r is not None:
            self.row(f"| {case.name} | build | {secs:.1f} s | | |")
            for f in sorted((d / "build").rglob("*")):
                if f.is_dir() or f.parent.name == "scans":
                    continue
                if f.suffix == ".mco":
                    self.read_mco(case, f, samples, partner(f, ".pop"))
                elif f.suffix == ".pop":
                    self.read_pop(case, f, samples, partner(f, ".mco"))
                elif f.suffix in (".ply", ".obj", ".stl", ".glb", ".xyz", ".pts"):
                    self.read_mesh_file(case.name, f, {})
                elif f.name == "lods.json":
                    self.read_lods_json(case.name, f)
                elif f.name == "report.html":
                    self.read_pictures(case.name, f)
        # mco build and pop encode, twice each (same bytes), then read back
        for i in (1, 2):
            self.run_ok(case.name, "mco build", "mco", "build", src, "-o", d / f"m{i}.mco")
            if case.kind != "scans":  # a scan set is merged by build and mco build only
                self.run_ok(case.name, "pop encode", "pop", "encode", src, "-o", d / f"p{i}.pop")
        m1, p1 = d / "m1.mco", d / "p1.pop"
        if m1.exists():
            self.read_mco(case, m1, samples, p1 if p1.exists() else None)
            self.same_bytes(case.name, "mco build", m1, d / "m2.mco")
            self.prefix(case, m1)
        if p1.exists():
            self.read_pop(case, p1, samples, m1 if m1.exists() else None)
            self.same_bytes(case.name, "pop encode", p1, d / "p2.pop")
        if case.kind == "mesh":
            self.lods(case, d)
        if case.kind in ("mesh", "points", "range"):
            self.convert(case, d)
        # render (twice)
        for i in ((1, 2) if case.kind != "scans" else ()):
            self.run_ok(case.name, "render", "render", src, "-o", d / f"r{i}.png")
        if (d / "r1.png").exists():
            self.same_bytes(case.name, "render", d / "r1.png", d / "r2.png")
            if Image is not None:
                f = shown_fraction(Image.open(d / "r1.png"))
                self.check(case.name, "render shows the model", f > 0.005, f"{f:.4f} of the pixels")
        print(f"-- {case.name}: done in {time.monotonic() - t:.0f} s", flush=True)

    def lods(self, case: Case, d: Path) -> None:
        for i in (1, 2):
            self.run_ok(case.name, "lods", "-q", "lods", case.path, "--out", d / f"lods{i}")
        j = d / "lods1" / "lods.json"
        if not j.exists():
            return
        self.read_lods_json(case.name, j)
        for f in sorted((d / "lods1").iterdir()):
            if f.suffix in (".ply", ".glb", ".obj"):
                want = {"attributes": ["colors"]} if case.colors else {}
                self.read_mesh_file(case.name, f, want)
            g = d / "lods2" / f.name
            if f.is_file() and f.name != "lods.json":
                self.same_bytes(case.name, f"lods {f.name}", f, g)

    def read_lods_json(self, case: str, j: Path) -> None:
        try:
            data = json.loads(j.read_text())
        except (OSError, json.JSONDecodeError) as e:
            self.check(case, f"{j.name} parses", False, str(e))
            return
        levels = data.get("levels", [])
        tris = [lv.get("triangles") for lv in levels]
        self.check(case, f"{j.parent.name}/lods.json: levels strictly fewer triangles each",
                   all(a > b for a, b in zip(tris, tris[1:])), str(tris))
        for lv in levels:
            f = lv.get("file")
            if f:
                self.check(case, f"lods.json names an existing {f}", (j.parent / f).exists())

    def convert(self, case: Case, d: Path) -> None:
        fmts = ["ply", "glb", "xyz", "pts"] if case.kind != "mesh" else ["ply", "obj", "stl", "glb"]
        for fmt in fmts:
            out = d / f"conv.{fmt}"
            r, _ = self.run_ok(case.name, f"convert to .{fmt}", "-q", "convert", case.path, out)
            if r is None:
                continue
            want = []
            if case.colors and fmt in ("ply", "glb"):
                want.append("colors")
            if case.uvs and fmt in ("obj", "glb", "ply"):
                want.append("uvs")
            got = self.read_mesh_file(case.name, out, {"attributes": want})
            again = d / "rerun" / f"conv.{fmt}"
            again.parent.mkdir(exist_ok=True)
            self.lodkit("-q", "convert", case.path, again)
            self.same_bytes(case.name, f"convert .{fmt}", out, again)

    def same_bytes(self, case: str, what: str, a: Path, b: Path) -> None:
        if not a.exists() or not b.exists():
            return
        self.check(case, f"{what}: a rerun gives the same bytes", sha(a) == sha(b))


def open_loops(ply: Path, diagonal: float) -> tuple[int, int, int]:
    """Boundary loops of a mesh file: (holes, seams, boundary edges). A
    seam is what a T-junction leaves (the surface is closed there, its
    triangles only do not share the edge's vertices): a loop of no vector
    area, or overlapping loops whose vector areas cancel (a thin part
    crossing cube faces whole, its outline once on each side). A hole is a
    group of overlapping loops whose summed vector area is over 1e-8 ×
    diagonal²."""
    import numpy as np

    if pylodkit is None:
        return (0, 0, 0)
    m = pylodkit.load(str(ply))
    if not hasattr(m, "faces"):  # a cut of no triangle reads as points
        return (0, 0, 0)
    f = np.asarray(m.faces, dtype=np.int64)
    v = np.asarray(m.vertices, dtype=np.float64)
    if len(f) == 0:
        return (0, 0, 0)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = np.minimum(e[:, 0], e[:, 1]) * (len(v) + 1) + np.maximum(e[:, 0], e[:, 1])
    uniq, counts = np.unique(key, return_counts=True)
    once = set(uniq[counts == 1].tolist())
    n_edges = len(once)
    nxt: dict[int, list[int]] = {}
    for (a, b), k in zip(e.tolist(), key.tolist()):
        if k in once:
            nxt.setdefault(a, []).append(b)
    limit = 1e-8 * diagonal * diagonal
    areas, boxes = [], []
    while nxt:
        start = next(iter(nxt))
        loop = [start]
        a = start
        while True:
            outs = nxt.get(a)
            if not outs:
                break
            b = outs.pop()
            if not outs:
                del nxt[a]
            a = b
            if a == start:
                break
            loop.append(a)
        p = v[loop]
        areas.append(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0) / 2)
        boxes.append((p.min(axis=0), p.max(axis=0)))
    if not areas:
        return (0, 0, n_edges)
    # A seam's outlines (the coarse side's and the finer sides', where a
    # part crosses cube faces whole) overlap and their vector areas cancel:
    # loops are grouped by overlapping bounds, and a group is a hole when
    # its summed vector area is not nil.
    lo = np.array([bx[0] for bx in boxes]) - 1e-6 * diagonal
    hi = np.array([bx[1] for bx in boxes]) + 1e-6 * diagonal
    parent = list(range(len(areas)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(len(areas)):
        touch = np.nonzero(np.all(lo[i] <= hi, axis=1) & np.all(lo <= hi[i], axis=1))[0]
        for j in touch[touch > i]:
            parent[find(int(j))] = find(i)
    groups: dict[int, np.ndarray] = {}
    for i, area in enumerate(areas):
        r = find(i)
        groups[r] = groups.get(r, np.zeros(3)) + area
    holes = sum(1 for g in groups.values() if np.linalg.norm(g) > limit)
    return holes, len(areas) - holes, n_edges


def shown_fraction(im) -> float:
    """The fraction of a picture's pixels that differ from its corner (the
    background) by more than a little."""
    import numpy as np

    a = np.asarray(im.convert("RGB"), dtype=np.int16)
    diff = np.abs(a - a[0, 0]).max(axis=2)
    return float((diff > 24).mean())


def partner(f: Path, suffix: str) -> Path | None:
    """The file beside `f` with `suffix` (the other streamed product)."""
    g = f.with_suffix(suffix)
    return g if g.exists() else None


def sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def wasm_read(wasm: str, jobs: list) -> list:
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(jobs, f)
    try:
        r = subprocess.run(["node", str(ROOT / "tests/conformance/wasm_read.mjs"), wasm, f.name],
                           capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            return [{"ok": False, "error": r.stderr.strip()[-300:]}]
        return json.loads(r.stdout)
    finally:
        os.unlink(f.name)


def native_digest(native: str | None, pop: Path, level: int, mco: Path, budget: int):
    """`native digest`: one .pop level and one .mco cut through the native
    library calls (the example takes both files at once)."""
    if not native:
        return None
    args = [native, "digest", str(pop), str(level), str(mco), str(budget)]
    r = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        return None
    return json.loads(r.stdout)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lodkit", required=True)
    ap.add_argument("--native")
    ap.add_argument("--wasm")
    ap.add_argument("--data", default=str(ROOT.parent / "shared/data"))
    ap.add_argument("--work", default=str(ROOT / "target/conformance"))
    ap.add_argument("--only")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    data = Path(args.data)
    if not data.is_dir():
        print(f"conformance: {data} is absent: only the shipped bunny is checked")
        data = None
    all_cases = cases(data)
    if args.only:
        keep = set(args.only.split(","))
        all_cases = [c for c in all_cases if c.name in keep]
    if pylodkit is None:
        print("conformance: pylodkit is not importable: its reads are skipped")
    if Image is None:
        print("conformance: Pillow is not importable: pictures are not checked")
    suite = Suite(args)
    t0 = time.monotonic()
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        for fut in [ex.submit(suite.run_case, c) for c in all_cases]:
            try:
                fut.result()
            except Exception as e:  # noqa: BLE001 - a crash of the suite is a failure
                suite.check("suite", "runs to the end", False, repr(e)[:300])
    print("\n| input | output | what | figure | against |\n|---|---|---|---|---|")
    for line in sorted(suite.table):
        print(line)
    print(f"\nconformance: {len(all_cases)} inputs in {time.monotonic() - t0:.0f} s")
    for line in suite.gaps:
        print(line)
    for line in suite.failed:
        print(line)
    print(f"{suite.passed} passed, {len(suite.failed)} failed")
    return 1 if suite.failed else 0


if __name__ == "__main__":
    sys.exit(main())
