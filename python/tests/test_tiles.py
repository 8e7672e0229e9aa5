"""pylodkit.tiles: the library's tiles job, its tileset read back."""
import json

import numpy as np
import pytest

import pylodkit as lk


def _walk(path, seen):
    doc = json.loads(path.read_text())
    assert doc["asset"]["version"] == "1.1"
    stack = [doc["root"]]
    while stack:
        t = stack.pop()
        uri = t.get("content", {}).get("uri")
        if uri and uri.endswith(".json"):
            _walk(path.parent / uri, seen)
        elif uri:
            f = path.parent / uri
            assert f.read_bytes()[:4] == b"glTF"
            seen.append((f, t))
        stack.extend(t.get("children", []))


def test_a_mesh_tileset_reads_back(tmp_path):
    src = tmp_path / "bunny.ply"
    lk.save(lk.bunny(), src)
    info = lk.tiles(src, tmp_path / "t", leaf_triangles=8000)
    assert info["kind"] == "mesh" and info["tiles"] >= 2
    tiles = []
    _walk(tmp_path / "t" / "tileset.json", tiles)
    assert len(tiles) == info["tiles"]
    assert all(t["refine"] == "REPLACE" for _, t in tiles)
    # Every tile reads back as a mesh with normals.
    for f, _ in tiles:
        m = lk.load(f)
        assert m.n_faces > 0 and m.normals is not None


def test_a_cloud_tileset_keeps_every_point(tmp_path):
    rng = np.random.default_rng(3)
    pts = rng.random((30_000, 3)).astype(np.float32)
    pts[:, 1] *= 0.05
    cols = rng.integers(0, 255, (30_000, 4), dtype=np.uint8)
    src = tmp_path / "cloud.ply"
    lk.save(lk.PointCloud(pts, colors=cols), src)
    info = lk.tiles(src, tmp_path / "t", leaf_points=4000)
    assert info["kind"] == "points" and info["points"] == 30_000
    tiles = []
    _walk(tmp_path / "t" / "tileset.json", tiles)
    total = 0
    for f, t in tiles:
        assert t["refine"] == "ADD"
        c = lk.load(f)
        assert c.colors is not None
        total += len(c)
    assert total == 30_000


def test_bad_options_and_a_users_folder_are_refused(tmp_path):
    src = tmp_path / "bunny.ply"
    lk.save(lk.bunny(), src)
    with pytest.raises(lk.OptionError):
        lk.tiles(src, tmp_path / "t", leaf_triangles=3)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(lk.LodkitError):
        lk.tiles(src, mine)
    assert (mine / "notes.txt").read_text() == "keep me"


def test_a_tiny_memory_tiles_out_of_core_with_the_same_bytes(tmp_path):
    src = tmp_path / "bunny.ply"
    lk.save(lk.bunny(), src)
    a = lk.tiles(src, tmp_path / "a", leaf_triangles=8000, memory=1 << 20)
    b = lk.tiles(src, tmp_path / "b", leaf_triangles=8000, memory=1 << 20)
    assert a["kind"] == "mesh" and a["tiles"] == b["tiles"] >= 2
    for f in (tmp_path / "a").rglob("*"):
        if f.is_file():
            assert f.read_bytes() == (tmp_path / "b" / f.relative_to(tmp_path / "a")).read_bytes()
    assert not [p for p in tmp_path.iterdir() if "lodkit-staging" in p.name]
    with pytest.raises(lk.OptionError):
        lk.tiles(src, tmp_path / "c", memory=12)
