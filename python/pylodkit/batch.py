"""LODs for a folder of assets: one task per asset, on Ray or, without it, here.

Command line::

    python -m pylodkit.batch IN_DIR OUT_DIR [--lods 0.5,0.25,0.1 | --levels N]
        [--pop] [--mco] [--address ADDR] [--workers N]

Every mesh file under ``IN_DIR`` (.ply .obj .stl .gltf .glb, searched
recursively) is one asset and one task. Its outputs go to
``OUT_DIR/<asset>/``, as ``lodkit lods`` writes a chain:
``<stem>_lod<i>.ply`` per level (each measured against the input) and
``<stem>_lods.glb`` (the input as level 0 and every level, an
``MSFT_lod`` chain with screen coverages and each level's error in its
extras); ``<stem>.pop`` with ``--pop``, ``<stem>.mco`` with ``--mco``;
then ``manifest.json``, written last. Every output is read back before
the asset is reported ``ok`` (each PLY level's triangles, the GLB's
chain, the stream decoded, the octree cut at full resolution): an output
that does not read back fails the asset. Every file is written
atomically (temporary file, fsync, rename), so an asset whose manifest
exists — with the same options and every listed file present at its
recorded size — is complete, and a rerun skips it (resume). A failing
asset (a malformed file, a point cloud where a mesh is needed, an output
that does not read back) is reported with its one-line message, leaves
no file and no folder of its own behind, and does not stop the batch. A
chain that stalls ends at its last new level, as ``lodkit lods`` does.
At the end ``OUT_DIR/summary.md``, ``summary.csv`` and ``summary.json``
list per asset: status, input and output triangles, the coarsest level's
measured mean error, time, and the error message; the table is printed
too. The exit status is 1 when an asset failed, else 0.

With Ray installed: without ``--address``, ``ray.init`` starts a local
cluster of ``--workers`` CPUs (default: all); with ``--address`` (``auto``
or ``HOST:PORT``) the batch runs on that cluster, keeping at most
``--workers`` tasks in flight. Each task is one core: lodkit's own
threads (rayon, used by the measurement) are limited to
``--threads-per-task`` (default 1). Without Ray, the assets are made
here, one after the other (one line says so; ``--address`` then is an
error).

From Python::

    >>> from pylodkit.batch import run_batch
    >>> summary = run_batch("assets/", "out/", ratios=[0.5, 0.1], pop=True, workers=2)
    >>> [row["status"] for row in summary["assets"]]
    ['ok', 'ok', 'failed']
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import io
import json
import os
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

MESH_EXTENSIONS = (".ply", ".obj", ".stl", ".gltf", ".glb")
MANIFEST = "manifest.json"
MANIFEST_VERSION = 2


def find_assets(in_dir: os.PathLike) -> List[Dict[str, str]]:
    """The mesh files under ``in_dir`` (sorted), each with its asset name.

    The asset name is the file's path relative to ``in_dir`` without its
    extension (``a/b.ply`` → ``a/b``); when two files share one (``b.ply``
    and ``b.obj``), the extension is kept for the later ones (``b.obj``).

    Example::

        >>> [a["name"] for a in find_assets("assets")]
        ['blob0', 'blob1', 'broken']
    """
    root = Path(in_dir)
    if not root.is_dir():
        raise NotADirectoryError("%s: not a directory" % root)
    files = sorted(p for p in root.rglob("*") if p.is_file() and p.suffix.lower() in MESH_EXTENSIONS)
    seen = set()
    out = []
    for p in files:
        rel = p.relative_to(root)
        name = rel.with_suffix("").as_posix()
        if name in seen:
            name = rel.as_posix()
        seen.add(name)
        out.append({"name": name, "path": str(p)})
    return out


def _options_key(opts: Dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(opts, sort_keys=True).encode()).hexdigest()[:16]


def _write_json(path: Path, value: Any) -> None:
    from . import _lodkit

    _lodkit.write_atomic(str(path), (json.dumps(value, indent=2, sort_keys=True) + "\n").encode())


def read_complete(asset_dir: Path, opts: Dict[str, Any]) -> Optional[Dict[str, Any]]:
    """The manifest of a complete asset made with ``opts``, else ``None``.

    Complete: the manifest parses, names the same options, and every
    output it lists exists with the size it recorded.

    Example::

        >>> read_complete(Path("out/blob0"), {"ratios": [0.5], "pop": False, "mco": False})
    """
    try:
        m = json.loads((asset_dir / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if m.get("version") != MANIFEST_VERSION or m.get("options_key") != _options_key(opts):
        return None
    for f in m.get("outputs", []):
        p = asset_dir / f["file"]
        try:
            if p.stat().st_size != f["bytes"]:
                return None
        except OSError:
            return None
    return m


def _glb_chain_ids(path: Path) -> List[int]:
    """The ``MSFT_lod`` ids on the scene's root node of a chain GLB."""
    b = path.read_bytes()
    if b[:4] != b"glTF" or len(b) < 20:
        raise ValueError("%s: not a GLB" % path)
    n = int.from_bytes(b[12:16], "little")
    j = json.loads(b[20:20 + n])
    base = j["nodes"][j["scenes"][j.get("scene", 0)]["nodes"][0]]
    return list(base.get("extensions", {}).get("MSFT_lod", {}).get("ids", []))


def _read_back(asset_dir: Path, checks: List[Tuple[str, str, Any]]) -> None:
    """Reads every output back; raises ``InputError`` naming the first one
    that does not read back as it was written. ``checks``: (file, kind,
    expected): ``ply`` (its triangles), ``glb`` ((level 0's triangles,
    levels behind MSFT_lod)), ``pop`` (None), ``mco`` (None)."""
    import pylodkit as lk

    for file, kind, want in checks:
        p = asset_dir / file
        if kind == "ply":
            m = lk.load(p)
            got = m.n_faces if isinstance(m, lk.Mesh) else None
            if got != want:
                raise lk.InputError("%s: reads back with %s triangles, %d were written" % (p, got, want))
        elif kind == "glb":
            m = lk.load(p)
            ids = _glb_chain_ids(p)
            got = (m.n_faces if isinstance(m, lk.Mesh) else None, len(ids))
            if got != tuple(want):
                raise lk.InputError("%s: reads back as level 0 of %s triangles with %d levels behind it, "
                                    "%d and %d were written" % (p, got[0], got[1], want[0], want[1]))
        elif kind == "pop":
            _, info = lk.pop.decode_with_info(p.read_bytes(), strict=True)
            if info["finest_level"] != info["depth"]:
                raise lk.InputError("%s: decodes to level %d of %d" % (p, info["finest_level"], info["depth"]))
        elif kind == "mco":
            model = lk.mco.load(p)
            cut = model.extract(lod=model.max_lod)
            if cut.n_faces != model.full_triangles:
                raise lk.InputError("%s: its full cut has %d triangles, the file says %d"
                                    % (p, cut.n_faces, model.full_triangles))


def _missing_dirs(asset_dir: Path, out_dir: Path) -> List[Path]:
    """The folders from ``asset_dir`` up to (not including) ``out_dir``
    that do not exist yet, deepest first: what ``mkdir(parents=True)``
    makes, and what a failure removes again when they are empty."""
    out = []
    d = asset_dir
    while d != out_dir and d != d.parent and not d.exists():
        out.append(d)
        d = d.parent
    return out


def process_asset(name: str, path: str, out_dir: str, opts: Dict[str, Any]) -> Dict[str, Any]:
    """Makes one asset's outputs (the body of each task); never raises.

    ``opts``: ``ratios`` (list of fractions), ``measure`` (bool),
    ``samples`` (int or None), ``pop`` (bool), ``mco`` (bool),
    ``resolution`` (int or None). Returns a summary row: ``asset``,
    ``status`` (``ok``, ``skipped`` or ``failed``), ``input_triangles``,
    ``triangles`` (per level), ``mean_error_pct`` (the coarsest level's
    measured mean distance, % of the input's diagonal), ``seconds`` and
    ``error`` (the one-line message of a failure). ``ok`` only once every
    output has been read back; a failure removes what this call wrote
    (files and the folders it made).

    Example::

        >>> process_asset("blob0", "assets/blob0.ply", "out", {"ratios": [0.5], "measure": True,
        ...               "samples": None, "pop": False, "mco": False, "resolution": None})["status"]
        'ok'
    """
    import numpy as np

    import pylodkit as lk
    from . import _lodkit

    t0 = time.perf_counter()
    asset_dir = Path(out_dir) / name
    row: Dict[str, Any] = {
        "asset": name, "input": path, "status": "failed", "input_triangles": None,
        "triangles": [], "mean_error_pct": None, "seconds": 0.0, "error": "",
    }
    done = read_complete(asset_dir, opts)
    if done is not None:
        row.update({k: done[k] for k in ("input_triangles", "triangles", "mean_error_pct")})
        row.update(status="skipped", seconds=0.0, made_seconds=done.get("seconds"))
        return row
    made_dirs = _missing_dirs(asset_dir, Path(out_dir))
    written: List[Path] = []
    try:
        geometry = lk.load(path)
        asset_dir.mkdir(parents=True, exist_ok=True)
        # An old manifest must not vouch for outputs being rewritten now.
        (asset_dir / MANIFEST).unlink(missing_ok=True)
        stem = Path(path).stem
        outputs: List[str] = []
        checks: List[Tuple[str, str, Any]] = []
        levels: List[Dict[str, Any]] = []

        def wrote(file: str, kind: str, want: Any) -> None:
            written.append(asset_dir / file)
            outputs.append(file)
            checks.append((file, kind, want))

        if opts["ratios"]:
            if not isinstance(geometry, lk.Mesh):
                raise lk.InputError("%s: holds a point cloud with no faces, a mesh is needed" % path)
            row["input_triangles"] = geometry.n_faces
            chain = lk.lod_chain(geometry, ratios=opts["ratios"], measure=opts["measure"],
                                 samples=opts["samples"])
            v = geometry.vertices
            diagonal = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0))) if len(v) else 0.0
            glb_levels = [(geometry, 0, (0.0, 0.0), 0.0)]
            for i, (mesh, report) in enumerate(chain, start=1):
                file = "%s_lod%d.ply" % (stem, i)
                lk.save(mesh, asset_dir / file)
                wrote(file, "ply", mesh.n_faces)
                levels.append(dict(report, file=file))
                if mesh.n_faces == 0:
                    continue
                mean, mx = report["measured_mean_error"], report["measured_max_error"]
                measured = (mean, mx) if mean is not None and mx is not None else None
                glb_levels.append((mesh, i, measured, float(report["estimated_error"])))
            glb = "%s_lods.glb" % stem
            _lodkit.write_lod_glb(str(asset_dir / glb), stem, glb_levels)
            wrote(glb, "glb", (geometry.n_faces, len(glb_levels) - 1))
            row["triangles"] = [lv["triangles"] for lv in levels]
            mean = levels[-1]["measured_mean_error"] if levels else None
            if mean is not None and diagonal > 0:
                row["mean_error_pct"] = mean / diagonal * 100.0
        elif isinstance(geometry, lk.Mesh):
            row["input_triangles"] = geometry.n_faces
        if opts["pop"]:
            file = stem + ".pop"
            _lodkit.write_atomic(str(asset_dir / file), lk.pop.encode(geometry))
            wrote(file, "pop", None)
        if opts["mco"]:
            file = stem + ".mco"
            lk.mco.build(geometry, resolution=opts["resolution"]).save(asset_dir / file)
            wrote(file, "mco", None)
        _read_back(asset_dir, checks)
        seconds = time.perf_counter() - t0
        manifest = {
            "version": MANIFEST_VERSION,
            "asset": name,
            "input": path,
            "options": opts,
            "options_key": _options_key(opts),
            "input_triangles": row["input_triangles"],
            "triangles": row["triangles"],
            "mean_error_pct": row["mean_error_pct"],
            "levels": levels,
            "seconds": seconds,
            "outputs": [{"file": f, "bytes": (asset_dir / f).stat().st_size} for f in outputs],
        }
        _write_json(asset_dir / MANIFEST, manifest)
        row.update(status="ok", seconds=seconds)
    except Exception as e:  # every failure becomes this asset's row
        # Nothing half-made stays: the files this call wrote, then the
        # folders it made, when they are empty.
        for p in written:
            try:
                p.unlink()
            except OSError:
                pass
        for d in made_dirs:
            try:
                d.rmdir()
            except OSError:
                break
        row.update(status="failed", seconds=time.perf_counter() - t0,
                   error=str(e).replace("\n", " ") or type(e).__name__)
    return row


def _table(rows: List[Dict[str, Any]]) -> str:
    out = ["| asset | status | input triangles | triangles per level | mean error (% diag) | seconds | error |",
           "|---|---|---:|---|---:|---:|---|"]
    for r in rows:
        err = r["mean_error_pct"]
        out.append("| %s | %s | %s | %s | %s | %.3f | %s |" % (
            r["asset"], r["status"],
            "" if r["input_triangles"] is None else r["input_triangles"],
            " / ".join(str(t) for t in r["triangles"]),
            "" if err is None else "%.4f" % err,
            r["seconds"], r["error"].replace("|", "\\|")))
    return "\n".join(out) + "\n"


def _csv(rows: List[Dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["asset", "status", "input_triangles", "triangles", "mean_error_pct", "seconds", "error"])
    for r in rows:
        w.writerow([r["asset"], r["status"], r["input_triangles"] if r["input_triangles"] is not None else "",
                    " ".join(str(t) for t in r["triangles"]),
                    "" if r["mean_error_pct"] is None else "%.6f" % r["mean_error_pct"],
                    "%.3f" % r["seconds"], r["error"]])
    return buf.getvalue()


def run_batch(
    in_dir: os.PathLike,
    out_dir: os.PathLike,
    *,
    ratios: Optional[Sequence[float]] = None,
    levels: Optional[int] = None,
    pop: bool = False,
    mco: bool = False,
    resolution: Optional[int] = None,
    measure: bool = True,
    samples: Optional[int] = None,
    address: Optional[str] = None,
    workers: Optional[int] = None,
    threads_per_task: int = 1,
    quiet: bool = False,
) -> Dict[str, Any]:
    """Runs the batch (see the module docs) and returns its summary.

    ``ratios`` or ``levels`` choose the LOD chain (default: 1/2, 1/4, 1/8;
    ``ratios=[]`` makes none; ratios must fall, else ``OptionError``);
    ``pop`` / ``mco`` add a ``.pop`` stream / ``.mco`` model per asset. The
    summary dict has ``assets`` (one row per asset, as
    :func:`process_asset` returns), ``ok``, ``skipped``, ``failed``,
    ``runner`` (``"ray"``, or ``"local"`` without Ray: the assets one after
    the other here), ``workers``, ``ray_init_seconds`` and ``wall_seconds``
    (from the first task submitted to the last result). Without Ray,
    ``address`` raises :class:`RayMissing`.

    Example::

        >>> s = run_batch("assets", "out", levels=2, workers=2)
        >>> s["failed"]
        0
    """
    from . import _check
    from ._core import check_ratios_fall

    if ratios is not None and levels is not None:
        raise ValueError("--lods and --levels conflict: give one of them")
    if ratios is None:
        n = _check.within("levels", 3 if levels is None else levels, "levels")
        ratios = [0.5 ** (i + 1) for i in range(n)]
    ratios = [_check.within("lods", r, "ratio") for r in ratios]
    check_ratios_fall("lods", ratios)
    _check.integer("workers", workers, 1, 4096)
    _check.integer("threads_per_task", threads_per_task, 1, 4096)
    opts = {"ratios": list(ratios), "measure": bool(measure), "samples": samples,
            "pop": bool(pop), "mco": bool(mco), "resolution": resolution}
    try:
        import ray
    except ImportError:
        ray = None
        if address:
            raise RayMissing("--address %s needs Ray, which is not installed here "
                             "(pip install ray)" % address)
    assets = find_assets(in_dir)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if ray is None:
        if not quiet:
            print("Ray is not installed: making the %d assets here, one after the other "
                  "(pip install ray to spread them over cores or machines)" % len(assets),
                  file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        rows: Dict[str, Dict[str, Any]] = {}
        for a in assets:
            row = process_asset(a["name"], a["path"], str(out), opts)
            rows[a["name"]] = row
            if not quiet:
                _print_row(row)
        return _finish(in_dir, out_dir, out, opts, assets, rows, "local", 1, 0.0,
                       time.perf_counter() - t0, quiet)

    env = {"RAYON_NUM_THREADS": str(threads_per_task)}
    t_init = time.perf_counter()
    started_here = False
    if not ray.is_initialized():
        if address:
            ray.init(address=address, runtime_env={"env_vars": env}, log_to_driver=False)
        else:
            # The local cluster's workers inherit the driver's environment.
            os.environ.update(env)
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False,
                     configure_logging=False)
        started_here = True
    ray_init_seconds = time.perf_counter() - t_init
    if workers is None:
        workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
    task = ray.remote(num_cpus=1, max_retries=0)(process_asset)

    rows: Dict[str, Dict[str, Any]] = {}
    pending = {}
    queue = list(assets)
    t0 = time.perf_counter()
    try:
        while queue or pending:
            while queue and len(pending) < workers:
                a = queue.pop(0)
                done = read_complete(out / a["name"], opts)
                if done is not None:  # resume: no task for a complete asset
                    rows[a["name"]] = process_asset(a["name"], a["path"], str(out), opts)
                    if not quiet:
                        print("skipped  %s (complete)" % a["name"], file=sys.stderr, flush=True)
                    continue
                ref = task.remote(a["name"], a["path"], str(out), opts)
                pending[ref] = a
            if not pending:
                continue
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                a = pending.pop(ref)
                try:
                    row = ray.get(ref)
                except Exception as e:  # a worker that died (killed, out of memory)
                    row = {"asset": a["name"], "input": a["path"], "status": "failed",
                           "input_triangles": None, "triangles": [], "mean_error_pct": None,
                           "seconds": 0.0, "error": str(e).strip().splitlines()[-1] if str(e).strip() else type(e).__name__}
                rows[a["name"]] = row
                if not quiet:
                    _print_row(row)
    finally:
        if started_here:
            ray.shutdown()
    return _finish(in_dir, out_dir, out, opts, assets, rows, "ray", workers, ray_init_seconds,
                   time.perf_counter() - t0, quiet)


class RayMissing(ImportError):
    """``address`` given where Ray is not installed."""


def _print_row(row: Dict[str, Any]) -> None:
    print("%-8s %s%s" % (row["status"], row["asset"], (": " + row["error"]) if row["error"] else ""),
          file=sys.stderr, flush=True)


def _finish(in_dir: os.PathLike, out_dir: os.PathLike, out: Path, opts: Dict[str, Any],
            assets: List[Dict[str, str]], rows: Dict[str, Dict[str, Any]], runner: str,
            workers: int, ray_init_seconds: float, wall: float, quiet: bool) -> Dict[str, Any]:
    """The summary of a run: written to ``summary.{md,csv,json}``, printed
    unless ``quiet``, returned."""
    ordered = [rows[a["name"]] for a in assets]
    summary = {
        "in_dir": str(in_dir),
        "out_dir": str(out_dir),
        "options": opts,
        "runner": runner,
        "workers": workers,
        "ray_init_seconds": ray_init_seconds,
        "wall_seconds": wall,
        "ok": sum(r["status"] == "ok" for r in ordered),
        "skipped": sum(r["status"] == "skipped" for r in ordered),
        "failed": sum(r["status"] == "failed" for r in ordered),
        "assets": ordered,
    }
    from . import _lodkit

    table = _table(ordered)
    foot = "\n%d assets: %d made, %d skipped (complete), %d failed; %d workers, %.2f s\n" % (
        len(ordered), summary["ok"], summary["skipped"], summary["failed"], workers, wall)
    _lodkit.write_atomic(str(out / "summary.md"), ("# lodkit batch\n\n" + table + foot).encode())
    _lodkit.write_atomic(str(out / "summary.csv"), _csv(ordered).encode())
    _write_json(out / "summary.json", summary)
    if not quiet:
        print(table + foot, end="")
    return summary


def _ratios(s: str) -> List[float]:
    try:
        return [float(x) for x in s.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("expected comma-separated fractions in [0, 1], e.g. 0.5,0.25,0.1")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line (``python -m pylodkit.batch --help``)."""
    from . import _check

    p = argparse.ArgumentParser(
        prog="python -m pylodkit.batch",
        description="LODs for every mesh file under IN_DIR, one task per asset (on Ray when it "
                    "is installed, else here, one after the other); reruns skip complete assets.")
    p.add_argument("in_dir", metavar="IN_DIR")
    p.add_argument("out_dir", metavar="OUT_DIR")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--lods", type=_ratios, metavar="R,R,...",
                   help="fractions of the input's triangles, one level each (default: 0.5,0.25,0.125)")
    g.add_argument("--levels", type=int, metavar="N", help="halving levels, %d..=%d (default 3)" % _check.LIMITS["levels"])
    p.add_argument("--pop", action="store_true", help="also write a .pop progressive stream")
    p.add_argument("--mco", action="store_true", help="also write a .mco continuous-LOD model")
    p.add_argument("--resolution", type=int, help="--mco lattice resolution, %d..=%d" % _check.LIMITS["resolution"])
    p.add_argument("--no-measure", action="store_true", help="skip the Metro error of each level")
    p.add_argument("--samples", type=int, help="samples per kind for the measured error")
    p.add_argument("--address", help="an existing Ray cluster (auto or HOST:PORT); default: a local one")
    p.add_argument("--workers", type=int, help="tasks at once (local cluster: its CPUs; default: all)")
    p.add_argument("--threads-per-task", type=int, default=1,
                   help="lodkit threads inside each task (default 1)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    a = p.parse_args(argv)
    from .errors import OptionError

    try:
        s = run_batch(a.in_dir, a.out_dir, ratios=a.lods, levels=a.levels, pop=a.pop, mco=a.mco,
                      resolution=a.resolution, measure=not a.no_measure, samples=a.samples,
                      address=a.address, workers=a.workers, threads_per_task=a.threads_per_task,
                      quiet=a.quiet)
    except (OptionError, ValueError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    except (OSError, RayMissing) as e:
        print("error: %s" % e, file=sys.stderr)
        return 1
    return 1 if s["failed"] else 0


if __name__ == "__main__":
    from pylodkit.batch import main as _main  # the importable module's tasks pickle by reference

    sys.exit(_main())
