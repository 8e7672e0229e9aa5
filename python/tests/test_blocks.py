"""Out-of-core blocks on Ray: `lodkit simplify --ray local` and `lodkit tiles
--ray local` give the bytes the single-process run gives; task files are
checked before they run."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import pylodkit as lk
from pylodkit import _lodkit
from pylodkit.errors import InputError

pytest.importorskip("ray")

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def lodkit_bin():
    exe = Path(os.environ.get("LODKIT_BIN", ROOT / "target" / "release" / "lodkit"))
    if not exe.is_file():
        pytest.skip("no lodkit binary (set LODKIT_BIN; scripts/ci-python.sh builds it)")
    return str(exe)


def simplify(exe, src, out, *extra):
    env = dict(os.environ, LODKIT_PYTHON=sys.executable)
    return subprocess.run([exe, "simplify", str(src), "-o", str(out), "--ratio", "0.1",
                           "--memory", "1M", *extra], env=env, capture_output=True, text=True)


def test_ray_blocks_give_the_single_process_bytes(lodkit_bin, tmp_path):
    src = tmp_path / "blob.ply"
    lk.save(lk.blob(40_000, seed=5), src)
    here = simplify(lodkit_bin, src, tmp_path / "threads.ply")
    assert here.returncode == 0, here.stderr
    assert "out of core" in here.stderr
    on_ray = simplify(lodkit_bin, src, tmp_path / "ray.ply", "--ray", "local")
    assert on_ray.returncode == 0, on_ray.stderr
    assert (tmp_path / "ray.ply").read_bytes() == (tmp_path / "threads.ply").read_bytes()
    # The staging folder (tasks.json, ray.log) is gone once the output is written.
    assert not [p for p in tmp_path.iterdir() if "lodkit-staging" in p.name]


def tiles(exe, src, out, *extra):
    env = dict(os.environ, LODKIT_PYTHON=sys.executable)
    return subprocess.run([exe, "tiles", str(src), "--out", str(out), "--memory", "1M", *extra],
                          env=env, capture_output=True, text=True)


def folder_bytes(folder):
    """Every file under `folder`, by its relative path, with its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_ray_tiles_give_the_single_process_bytes(lodkit_bin, tmp_path):
    src = tmp_path / "blob.ply"
    lk.save(lk.blob(40_000, seed=5), src)
    here = tiles(lodkit_bin, src, tmp_path / "threads")
    assert here.returncode == 0, here.stderr
    assert "out of core" in here.stderr
    on_ray = tiles(lodkit_bin, src, tmp_path / "ray", "--ray", "local")
    assert on_ray.returncode == 0, on_ray.stderr
    threads = folder_bytes(tmp_path / "threads")
    ray = folder_bytes(tmp_path / "ray")
    assert "tileset.json" in threads and len(threads) > 2
    assert sorted(ray) == sorted(threads)
    differ = [name for name in threads if ray[name] != threads[name]]
    assert not differ, f"{len(differ)} of {len(threads)} files differ: {differ[:5]}"
    # The staging folders are gone once the tilesets are written.
    assert not [p for p in tmp_path.iterdir() if "lodkit-staging" in p.name]


def task_file(path, name):
    path.write_text(json.dumps({
        "version": 4,
        "options": {"max_error": None, "heap_size": 1,
                    "weights": {"normal": 0.0, "color": 0.0, "uv": 0.0},
                    "prune": None, "max_passes": 64},
        "layout": "-",
        "tasks": [{"input": name, "output": "b.out", "ratio": 0.5, "goal": "total",
                   "cuts": {"min": [0, 0, 0], "cell": [1, 1, 1], "g": 2, "shift": 0, "reach": 0.5},
                   "faces": 1}],
    }))


def test_a_task_file_cannot_name_a_file_outside_its_folder(tmp_path):
    tasks = tmp_path / "tasks.json"
    for name in ["../secret.in", "/etc/passwd", ".."]:
        task_file(tasks, name)
        with pytest.raises(InputError, match="plain file name"):
            _lodkit.block_task_count(str(tasks))
    task_file(tasks, "b.in")
    assert _lodkit.block_task_count(str(tasks)) == 1
    with pytest.raises(InputError, match="task 3"):
        _lodkit.run_block_task(str(tasks), 3)


def test_the_runner_reports_a_bad_task_file_in_one_line(tmp_path):
    bad = tmp_path / "tasks.json"
    bad.write_text("{")
    r = subprocess.run([sys.executable, "-m", "pylodkit.blocks", str(bad)],
                       capture_output=True, text=True)
    assert r.returncode == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "not a block task file" in lines[0], r.stderr
