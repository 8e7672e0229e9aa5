"""The library's jobs on files: build, compare, render, info, simplify and
lod_chain of a path, their progress events and their errors."""
import json
import os
import struct
import subprocess
from pathlib import Path

import pytest

import pylodkit as lk

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def lodkit_bin():
    exe = Path(os.environ.get("LODKIT_BIN", ROOT / "target" / "release" / "lodkit"))
    if not exe.is_file():
        pytest.skip("no lodkit binary (set LODKIT_BIN; scripts/ci-python.sh builds it)")
    return str(exe)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The shipped bunny as a binary PLY, a tenth of it, a .mco and a .pop."""
    d = tmp_path_factory.mktemp("jobs")
    bunny = lk.bunny()
    lk.save(bunny, d / "bunny.ply")
    lod, _ = lk.simplify(bunny, ratio=0.1)
    lk.save(lod, d / "lod.ply")
    lk.mco.build(lod, resolution=32).save(d / "lod.mco")
    (d / "lod.pop").write_bytes(lk.pop.encode(lod, depth=6))
    return d


class Events:
    """A progress callback that keeps every event."""

    def __init__(self):
        self.events = []

    def __call__(self, e):
        assert isinstance(e, dict) and "event" in e
        self.events.append(e)

    def kinds(self):
        return [e["event"] for e in self.events]


def check_stages(events):
    """Every stage started is finished, in order, with a time."""
    open_ = []
    for e in events:
        if e["event"] == "stage_started":
            open_.append(e["name"])
        elif e["event"] == "stage_finished":
            assert open_ and open_.pop() == e["name"] and e["seconds"] >= 0
    assert not open_


def untimed(v):
    """``v`` without its wall times (keys ending in ``seconds``)."""
    if isinstance(v, dict):
        return {k: untimed(x) for k, x in v.items() if not k.endswith("seconds")}
    if isinstance(v, list):
        return [untimed(x) for x in v]
    return v


def png_size(path):
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_build_bunny_reads_back_every_product(tmp_path):
    ev = Events()
    out = tmp_path / "bunny_lods"
    r = lk.build(None, out, levels=3, samples=20_000, progress=ev)
    assert r["model"] == "stanford_bunny"
    names = [f for f, _ in r["outputs"]]
    for f, size in r["outputs"]:
        assert (out / f).stat().st_size == size, f
    read = set()
    for f in names:
        p = out / f
        if p.suffix in (".ply", ".glb", ".obj"):
            g = lk.load(p)
            assert (g.n_faces if isinstance(g, lk.Mesh) else len(g)) > 0, f
        elif p.suffix == ".mco":
            assert lk.mco.load(p).full_triangles > 0
        elif p.suffix == ".pop":
            assert lk.pop.decode(p.read_bytes()).n_faces > 0
        elif p.suffix == ".json":
            json.loads(p.read_text())
        elif p.suffix in (".md", ".html"):
            assert "stanford_bunny" in p.read_text()
        elif p.suffix == ".png":
            png_size(p)
        else:
            continue
        read.add(p.suffix)
    assert {".ply", ".glb", ".mco", ".pop", ".json", ".md", ".html"} <= read
    assert len([f for f in names if "_lod" in f and f.endswith(".ply")]) == 3
    check_stages(ev.events)
    assert "stage_started" in ev.kinds()


def test_build_refuses_a_folder_it_did_not_make(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    with pytest.raises(lk.OptionError) as e:
        lk.build(None, out, levels=1, measure=False)
    assert str(out) in str(e.value)
    assert (out / "notes.txt").read_text() == "keep me"
    with pytest.raises(lk.OptionError, match=r"levels=0: expected an integer in 1\.\.=32"):
        lk.build(None, tmp_path / "x", levels=0)


def test_compare_equals_the_cli(files, lodkit_bin):
    a, b = files / "bunny.ply", files / "lod.ply"
    ev = Events()
    r = lk.compare(a, b, samples=20_000, progress=ev)
    cli = subprocess.run([lodkit_bin, "compare", str(a), str(b), "--samples", "20000", "--json"],
                         check=True, capture_output=True, text=True)
    assert r == json.loads(cli.stdout)
    check_stages(ev.events)
    # The in-memory form measures the same numbers.
    ev2 = Events()
    mem = lk.compare(lk.load(a), lk.load(b), samples=20_000, progress=ev2)
    assert mem == {k: v for k, v in r.items() if k != "heatmap"}
    check_stages(ev2.events)
    assert "stage_started" in ev2.kinds()


def test_compare_heatmap(files, tmp_path):
    heat = tmp_path / "heat.ply"
    r = lk.compare(files / "bunny.ply", files / "lod.ply", samples=10_000, heatmap=heat)
    assert r["heatmap"]["vertices"] == lk.load(heat).n_vertices
    assert lk.load(heat).colors is not None
    with pytest.raises(lk.OptionError, match="heat map"):
        lk.compare(files / "bunny.ply", files / "lod.ply", heatmap=tmp_path / "h.stl")
    with pytest.raises(lk.OptionError, match="two paths or two meshes"):
        lk.compare(files / "bunny.ply", lk.bunny())


def test_render_writes_a_png(files, tmp_path):
    for name, extra in [("lod.ply", {}), ("lod.mco", {"lod": 3}), ("lod.pop", {"level": 4})]:
        png = tmp_path / (name + ".png")
        ev = Events()
        r = lk.render(files / name, png, size=(96, 64), progress=ev, **extra)
        assert png_size(png) == (96, 64)
        assert r["views"] == 1 and r["output"] == str(png) and 0 < r["coverage"] < 1
        check_stages(ev.events)
    with pytest.raises(lk.OptionError, match="apply to .mco models"):
        lk.render(files / "lod.ply", tmp_path / "x.png", lod=2)
    with pytest.raises(lk.OptionError, match=r"fov=200: expected a number in \[1, 170\]"):
        lk.render(files / "lod.ply", tmp_path / "x.png", fov=200)
    # A cut outside the model: the library's message.
    with pytest.raises(lk.OptionError, match="is outside 0..="):
        lk.render(files / "lod.mco", tmp_path / "x.png", lod=10**6)
    assert not (tmp_path / "x.png").exists()


def test_info_of_mesh_mco_pop(files, lodkit_bin):
    mesh = lk.info(files / "lod.ply")
    assert mesh["faces"] == lk.load(files / "lod.ply").n_faces
    mco = lk.info(files / "lod.mco")
    assert mco["version"] >= 1 and mco["lod_numbers"] == lk.mco.load(files / "lod.mco").max_lod
    ev = Events()
    pop = lk.info(files / "lod.pop", progress=ev)
    assert pop and "stage_started" in ev.kinds()
    for name, got in [("lod.ply", mesh), ("lod.mco", mco), ("lod.pop", pop)]:
        cli = subprocess.run([lodkit_bin, "info", str(files / name), "--json"],
                             check=True, capture_output=True, text=True)
        assert untimed(got) == untimed(json.loads(cli.stdout)), name
    with pytest.raises(lk.InputError, match="not_a_model"):
        bad = files / "not_a_model.ply"
        bad.write_bytes(b"ply\nnonsense\n")
        lk.info(bad)


def test_simplify_file_out_of_core_progress_is_monotone(files, tmp_path):
    ev = Events()
    out = tmp_path / "ooc.ply"
    r = lk.simplify(files / "bunny.ply", ratio=0.1, output=out, memory=1 << 20, progress=ev)
    assert r["out_of_core"] is not None and r["triangles"] == lk.load(out).n_faces
    phases = 0
    last = None
    for e in ev.events:
        if e["event"] == "phase":
            phases += 1
            last = 0
        elif e["event"] == "advance":
            assert e["n"] >= 0 and e["done"] >= last and e["done"] <= e["len"]
            last = e["done"]
    assert phases > 0 and "advance" in ev.kinds()
    # In core: the same job, the same report keys the CLI prints.
    r2 = lk.simplify(str(files / "bunny.ply"), ratio=0.1, output=tmp_path / "in.ply")
    assert "out_of_core" not in r2 and r2["triangles"] == lk.load(tmp_path / "in.ply").n_faces
    with pytest.raises(lk.OptionError, match="output"):
        lk.simplify(files / "bunny.ply", ratio=0.1)
    with pytest.raises(lk.OptionError, match="memory"):
        lk.simplify(files / "bunny.ply", ratio=0.1, output=out, memory=1)


def test_lod_chain_file_sends_each_level(files, tmp_path):
    ev = Events()
    out = tmp_path / "chain"
    r = lk.lod_chain(files / "bunny.ply", 3, out=out, samples=10_000, progress=ev)
    levels = [e["level"] for e in ev.events if e["event"] == "level"]
    assert [l["level"] for l in levels] == [1, 2, 3] == [l["level"] for l in r["levels"]]
    tris = [l["triangles"] for l in r["levels"]]
    assert tris == sorted(tris, reverse=True)
    for l in r["levels"]:
        assert lk.load(out / l["file"]).n_faces == l["triangles"]
    assert (out / "lods.json").is_file() and lk.load(out / r["glb"]).n_faces > 0
    with pytest.raises(lk.OptionError, match="each level must be smaller"):
        lk.lod_chain(files / "bunny.ply", ratios=[0.5, 0.6], out=out)


def test_in_memory_simplify_reports_its_stage():
    ev = Events()
    lod, report = lk.simplify(lk.icosphere(3), ratio=0.5, progress=ev)
    assert lod.n_faces == report["triangles"]
    assert [(e["event"], e["name"]) for e in ev.events] == [
        ("stage_started", "simplifying"), ("stage_finished", "simplifying")]


def test_progress_errors(files, tmp_path):
    with pytest.raises(lk.OptionError, match="progress"):
        lk.info(files / "lod.ply", progress=3)
    calls = []

    def boom(e):
        calls.append(e)
        raise RuntimeError("stop")

    # The job runs to its end (its output whole); then the exception.
    png = tmp_path / "boom.png"
    with pytest.raises(RuntimeError, match="stop"):
        lk.render(files / "lod.ply", png, size=(32, 32), progress=boom)
    assert len(calls) == 1 and png_size(png) == (32, 32)


def test_mco_build_is_the_cli_build(files, tmp_path, lodkit_bin):
    ev = Events()
    model = lk.mco.build(files / "lod.ply", progress=ev)
    out = tmp_path / "cli.mco"
    subprocess.run([lodkit_bin, "mco", "build", str(files / "lod.ply"), "-o", str(out)],
                   check=True, capture_output=True)
    assert model.to_bytes() == out.read_bytes()
    notes = [e["message"] for e in ev.events if e["event"] == "note"]
    assert any(n.startswith("lattice: resolution") for n in notes)
    assert any(n.startswith("added %s" % (files / "lod.ply")) for n in notes)
    check_stages(ev.events)


def test_jobs_write_the_cli_bytes(files, tmp_path, lodkit_bin):
    def cli(*args):
        subprocess.run([lodkit_bin, *map(str, args)], check=True, capture_output=True)

    # build: every file but the two holding wall times (and the manifest
    # listing their sizes) is the CLI's, byte for byte.
    r = lk.build(files / "lod.ply", tmp_path / "py", levels=2, samples=5_000)
    cli("build", files / "lod.ply", "--out", tmp_path / "cli", "--levels", "2", "--samples", "5000")
    timed = {"lods/lods.json", "report.html", ".lodkit-build.json"}
    def made(d):
        return sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file())

    listed = made(tmp_path / "py")
    assert listed == made(tmp_path / "cli")
    assert {f for f, _ in r["outputs"]} <= set(listed)
    for f in listed:
        if f not in timed:
            assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    # simplify and render of a file.
    lk.simplify(files / "bunny.ply", 3000, output=tmp_path / "py.glb")
    cli("simplify", files / "bunny.ply", "-o", tmp_path / "cli.glb", "--target", "3000")
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    lk.render(files / "lod.mco", tmp_path / "py.png", size=(64, 48), azimuth=-40, elevation=10)
    cli("render", files / "lod.mco", "-o", tmp_path / "cli.png", "--size", "64x48",
        "--view=-40,10")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()


def test_batch_chain_glb_is_the_cli_one(files, tmp_path, lodkit_bin):
    from pylodkit.batch import process_asset

    opts = {"ratios": [0.5, 0.25], "measure": True, "samples": None, "pop": False,
            "mco": False, "resolution": None}
    r = process_asset("lod", str(files / "lod.ply"), str(tmp_path / "batch"), opts)
    assert r["status"] == "ok", r
    subprocess.run([lodkit_bin, "lods", str(files / "lod.ply"), "--out", str(tmp_path / "cli"),
                    "--ratios", "0.5,0.25"], check=True, capture_output=True)
    assert ((tmp_path / "batch" / "lod" / "lod_lods.glb").read_bytes()
            == (tmp_path / "cli" / "lod_lods.glb").read_bytes())
