"""Continuous LOD models and progressive streams."""
import numpy as np
import pytest

import pylodkit as lk


@pytest.fixture(scope="module")
def model(sphere):
    return lk.mco.build(sphere, resolution=32)


def test_mco_cuts(model):
    assert model.max_lod > 0 and model.full_triangles > 0
    full = model.extract(lod=model.max_lod)
    assert full.n_faces == model.full_triangles == model.triangles_at_lod(model.max_lod)
    some = model.extract(triangles=model.full_triangles // 4)
    assert 0 < some.n_faces <= model.full_triangles
    near = model.extract(view=(0.0, 0.0, 3.0), tolerance=2.0)
    assert 0 < near.n_faces <= model.full_triangles
    info = model.info()
    assert info["lod_numbers"] == model.max_lod and info["full_triangles"] == model.full_triangles


def test_mco_files_and_bytes(tmp_path, model):
    p = tmp_path / "s.mco"
    model.save(p)
    back = lk.mco.load(p)
    assert back.max_lod == model.max_lod
    assert p.read_bytes() == model.to_bytes()
    again = lk.mco.from_bytes(model.to_bytes())
    assert np.array_equal(again.extract(lod=3).faces, model.extract(lod=3).faces)
    with pytest.raises(lk.InputError):
        lk.mco.from_bytes(b"not an mco file")
    with pytest.raises(lk.FileError):
        lk.mco.load(tmp_path / "missing.mco")


def test_mco_options(model, sphere):
    with pytest.raises(lk.OptionError, match="exactly one"):
        model.extract()
    with pytest.raises(lk.OptionError, match="exactly one"):
        model.extract(lod=1, triangles=5)
    with pytest.raises(lk.OptionError, match="outside 0..="):
        model.extract(lod=model.max_lod + 1)
    with pytest.raises(lk.OptionError, match="give view="):
        model.extract(lod=1, tolerance=2)
    with pytest.raises(lk.OptionError, match=r"resolution=1: expected an integer in 2..=512"):
        lk.mco.build(sphere, resolution=1)


def test_mco_from_points(sphere):
    pts = lk.PointCloud(sphere.vertices, normals=sphere.normals)
    m = lk.mco.build(pts, resolution=24)
    assert m.full_triangles > 0


def test_pop_round_trip(sphere):
    data, report = lk.pop.encode_with_report(sphere, depth=6)
    assert isinstance(data, bytes) and report["total_bytes"] == len(data)
    assert data == lk.pop.encode(sphere, depth=6)  # deterministic
    mesh, info = lk.pop.decode_with_info(data)
    assert isinstance(mesh, lk.Mesh) and info["level"] == info["finest_level"] == 6
    assert info["cut"] is None and mesh.n_faces == info["triangles"] > 0
    coarse = lk.pop.decode(data, level=3)
    assert coarse.n_faces < mesh.n_faces
    pts = lk.pop.decode(data, points=True)
    assert isinstance(pts, lk.PointCloud) and len(pts) == info["particles"]


def test_pop_prefix_and_errors(sphere):
    data = lk.pop.encode(sphere, depth=6)
    part, info = lk.pop.decode_with_info(data[: len(data) // 2])
    assert info["cut"] is not None and info["bytes_read"] <= len(data) // 2
    assert info["cut"]["offset"] == info["bytes_read"] and part.n_faces > 0
    with pytest.raises(lk.InputError, match="invalid .pop stream"):
        lk.pop.decode(data[: len(data) // 2], strict=True)
    with pytest.raises(lk.InputError):
        lk.pop.decode(b"garbage")
    with pytest.raises(lk.OptionError, match="precision=4 is below depth=6"):
        lk.pop.encode(sphere, depth=6, precision=4)
    with pytest.raises(lk.OptionError, match="depth=13"):
        lk.pop.encode(sphere, depth=13)


def test_pop_from_a_point_array():
    pts = np.random.default_rng(3).normal(size=(4000, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    data = lk.pop.encode(pts, depth=5)
    assert lk.pop.decode(data).n_faces > 0


def test_pop_of_a_cloud_keeps_its_detail():
    # A cloud is coded from its reconstructed surface at about one particle
    # per point (as `lodkit pop encode` does); raw=True codes the samples.
    rng = np.random.default_rng(5)
    pts = rng.normal(size=(20000, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    data, report = lk.pop.encode_with_report(pts)
    assert report["source"] == "surface"
    assert 10000 <= report["particles"] <= 40000
    assert lk.pop.decode(data).n_faces > 0
    raw, report = lk.pop.encode_with_report(pts, raw=True)
    assert report["source"] == "samples" and raw != data
