"""The batch: one task per asset (on Ray, or here without it), every
output read back, failures reported and leaving nothing, resume."""
import json
import os
import subprocess
import sys

import pytest

import pylodkit as lk
from pylodkit.batch import find_assets, run_batch

# Runs the batch's command line in a Python where `import ray` fails.
NO_RAY = ("import sys; sys.modules['ray'] = None; "
          "from pylodkit.batch import main; sys.exit(main(sys.argv[1:]))")


@pytest.fixture(scope="module")
def assets(tmp_path_factory):
    d = tmp_path_factory.mktemp("assets")
    for i in range(3):
        lk.save(lk.blob(2_000 + 500 * i, seed=i + 1), d / ("blob%d.ply" % i))
    (d / "sub").mkdir()
    lk.save(lk.icosphere(3), d / "sub" / "ico.obj")
    (d / "broken.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    (d / "notes.txt").write_text("not an asset")
    return d


@pytest.fixture(scope="module")
def cluster():
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()


def rows(summary):
    return {r["asset"]: r for r in summary["assets"]}


def test_find_assets(assets):
    assert [a["name"] for a in find_assets(assets)] == ["blob0", "blob1", "blob2", "broken", "sub/ico"]


def test_batch_failure_and_resume(assets, tmp_path, cluster):
    out = tmp_path / "out"
    s = run_batch(assets, out, ratios=[0.5, 0.25], pop=True, mco=True, resolution=24, workers=2,
                  quiet=True)
    r = rows(s)
    assert (s["ok"], s["failed"], s["skipped"]) == (4, 1, 0)
    assert r["broken"]["status"] == "failed" and str(assets / "broken.ply") in r["broken"]["error"]
    assert "\n" not in r["broken"]["error"]
    b0 = r["blob0"]
    assert b0["input_triangles"] > 0 and len(b0["triangles"]) == 2 and b0["mean_error_pct"] > 0
    files = sorted(os.listdir(out / "blob0"))
    assert files == ["blob0.mco", "blob0.pop", "blob0_lod1.ply", "blob0_lod2.ply", "blob0_lods.glb",
                     "manifest.json"]
    assert not (out / "broken").exists()  # a failed asset leaves no folder
    assert (out / "sub" / "ico" / "ico_lod1.ply").exists()
    for name in ("summary.md", "summary.csv", "summary.json"):
        assert (out / name).exists()
    assert "| broken | failed |" in (out / "summary.md").read_text()
    assert json.loads((out / "summary.json").read_text())["failed"] == 1

    # Rerun: the complete assets are skipped, the broken one fails again.
    s2 = run_batch(assets, out, ratios=[0.5, 0.25], pop=True, mco=True, resolution=24, workers=2,
                   quiet=True)
    assert (s2["ok"], s2["skipped"], s2["failed"]) == (0, 4, 1)
    assert rows(s2)["blob0"]["triangles"] == b0["triangles"]

    # An output that went missing (or a manifest never written) is made again.
    (out / "blob1" / "blob1.pop").unlink()
    (out / "blob2" / "manifest.json").unlink()
    s3 = run_batch(assets, out, ratios=[0.5, 0.25], pop=True, mco=True, resolution=24, workers=2,
                   quiet=True)
    r3 = rows(s3)
    assert r3["blob1"]["status"] == "ok" and r3["blob2"]["status"] == "ok"
    assert r3["blob0"]["status"] == "skipped" and s3["failed"] == 1

    # Other options are other outputs: nothing is skipped.
    s4 = run_batch(assets, out, ratios=[0.1], workers=1, quiet=True)
    assert s4["skipped"] == 0 and s4["ok"] == 4


def test_batch_command_line(assets, tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "cli"
    cmd = [sys.executable, "-m", "pylodkit.batch", str(assets), str(out), "--lods", "0.5",
           "--workers", "2", "--no-measure"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 1, p.stderr  # the broken asset
    assert "| broken | failed |" in p.stdout and "4 made, 0 skipped (complete), 1 failed" in p.stdout
    bad = subprocess.run(cmd + ["--levels", "2"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "not allowed with" in bad.stderr


def glb_json(path):
    b = path.read_bytes()
    n = int.from_bytes(b[12:16], "little")
    return json.loads(b[20:20 + n])


def test_without_ray_the_batch_runs_here_and_writes_the_glb_chain(assets, tmp_path):
    out = tmp_path / "local"
    cmd = [sys.executable, "-c", NO_RAY, str(assets), str(out), "--lods", "0.5,0.2", "--pop"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 1, p.stderr  # the broken asset
    assert "Traceback" not in p.stderr, p.stderr
    assert [l for l in p.stderr.splitlines() if "Ray is not installed" in l], p.stderr
    assert "4 made, 0 skipped (complete), 1 failed" in p.stdout
    assert json.loads((out / "summary.json").read_text())["runner"] == "local"
    assert not (out / "broken").exists()
    # The GLB chain as `lodkit lods` writes it: the input as level 0, each
    # level behind MSFT_lod, strictly falling screen coverages.
    m = json.loads((out / "blob1" / "manifest.json").read_text())
    assert [o["file"] for o in m["outputs"]] == ["blob1_lod1.ply", "blob1_lod2.ply", "blob1_lods.glb",
                                                 "blob1.pop"]
    j = glb_json(out / "blob1" / "blob1_lods.glb")
    base = j["nodes"][j["scenes"][0]["nodes"][0]]
    assert base["name"] == "blob1_LOD0" and base["extras"]["triangles"] == m["input_triangles"]
    ids = base["extensions"]["MSFT_lod"]["ids"]
    assert [j["nodes"][i]["extras"]["triangles"] for i in ids] == m["triangles"]
    assert j["nodes"][ids[1]]["extras"]["error"]["measured"] is True
    cover = base["extras"]["MSFT_screencoverage"]
    assert len(cover) == 3 and all(b < a for a, b in zip(cover, cover[1:])) and cover[-1] == 0
    assert lk.load(out / "blob1" / "blob1_lods.glb").n_faces == m["input_triangles"]
    # --address needs Ray: one line, exit 1.
    p = subprocess.run(cmd + ["--address", "auto"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert p.stderr.strip().count("\n") == 0 and "needs Ray" in p.stderr, p.stderr
    # Ratios that do not fall: a usage error.
    p = subprocess.run(cmd[:-3] + ["--lods", "0.2,0.5"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "smaller than the one before" in p.stderr, p.stderr


def test_an_output_that_does_not_read_back_fails_its_asset_and_leaves_nothing(assets, tmp_path,
                                                                             monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)

    def unreadable(data, *a, **k):
        raise lk.InputError("stream: cannot be decoded (test)")

    monkeypatch.setattr(lk.pop, "decode_with_info", unreadable)
    out = tmp_path / "bad"
    s = run_batch(assets, out, ratios=[0.5], pop=True, quiet=True)
    assert s["runner"] == "local" and s["ok"] == 0 and s["failed"] == 5
    r = rows(s)["blob0"]
    assert "cannot be decoded" in r["error"], r
    assert sorted(os.listdir(out)) == ["summary.csv", "summary.json", "summary.md"]
    # Without the failing check the same run makes every asset but the broken one.
    monkeypatch.undo()
    monkeypatch.setitem(sys.modules, "ray", None)
    s = run_batch(assets, out, ratios=[0.5], pop=True, quiet=True)
    assert (s["ok"], s["failed"]) == (4, 1)
