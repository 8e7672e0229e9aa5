"""The Ray batch: one task per asset, failures reported, resume."""
import json
import os
import subprocess
import sys

import pytest

import pylodkit as lk

ray = pytest.importorskip("ray")
from pylodkit.batch import find_assets, run_batch  # noqa: E402


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
    assert files == ["blob0.mco", "blob0.pop", "blob0_lod1.ply", "blob0_lod2.ply", "manifest.json"]
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
    out = tmp_path / "cli"
    cmd = [sys.executable, "-m", "pylodkit.batch", str(assets), str(out), "--lods", "0.5",
           "--workers", "2", "--no-measure"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 1, p.stderr  # the broken asset
    assert "| broken | failed |" in p.stdout and "4 made, 0 skipped (complete), 1 failed" in p.stdout
    bad = subprocess.run(cmd + ["--levels", "2"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "not allowed with" in bad.stderr
