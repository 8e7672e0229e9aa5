"""trimesh and open3d round trips (skipped where the package is missing)."""
import numpy as np
import pytest

import pylodkit as lk


def importorskip(name):
    """The module, or a skip when it is missing or cannot load (open3d
    needs system libraries such as libusb that a bare machine may lack)."""
    try:
        return __import__(name)
    except Exception as e:  # ImportError, OSError from a missing .so
        pytest.skip("%s is not usable here: %s" % (name, e))


def test_trimesh_round_trip(sphere):
    trimesh = importorskip("trimesh")
    tm = lk.to_trimesh(sphere)
    assert isinstance(tm, trimesh.Trimesh) and len(tm.faces) == sphere.n_faces
    back = lk.from_trimesh(tm)
    assert np.array_equal(back.faces, sphere.faces.astype(np.int64))
    assert np.allclose(back.vertices, sphere.vertices)
    assert back.colors is not None and np.array_equal(back.colors, sphere.colors)
    # A Trimesh passed straight in is read as from_trimesh reads it: its
    # vertex colours come along (and give the same result).
    lod, _ = lk.simplify(tm, ratio=0.25)
    via, _ = lk.simplify(lk.from_trimesh(tm), ratio=0.25)
    lod2, _ = lk.simplify(sphere, ratio=0.25)
    assert lod.n_faces == lod2.n_faces
    assert lod.colors is not None and np.array_equal(lod.colors, via.colors)
    assert np.array_equal(lod.faces, via.faces)
    assert lk.to_trimesh(lod).is_watertight
    chain = lk.lod_chain(tm, ratios=[0.5], measure=False)
    assert chain[0][0].colors is not None


def test_trimesh_uvs():
    trimesh = importorskip("trimesh")
    m = lk.icosphere(2)
    uvs = (m.vertices[:, :2] * 0.5 + 0.5).astype(np.float32)
    tm = lk.to_trimesh(lk.Mesh(m.vertices, m.faces, uvs=uvs))
    back = lk.from_trimesh(tm)
    assert back.uvs is not None and np.allclose(back.uvs, uvs)


def test_open3d_round_trip(sphere):
    o3d = importorskip("open3d")
    om = lk.to_open3d(sphere)
    assert len(om.triangles) == sphere.n_faces and om.has_vertex_colors()
    back = lk.from_open3d(om)
    assert np.array_equal(back.faces, sphere.faces.astype(np.int32))
    assert np.allclose(back.vertices, sphere.vertices)
    assert np.abs(back.colors[:, :3] * 255 - sphere.colors[:, :3]).max() < 0.51
    lod, _ = lk.simplify(back, ratio=0.5)
    assert lod.n_faces <= sphere.n_faces // 2
    pc = lk.to_open3d(lk.PointCloud(sphere.vertices))
    assert isinstance(pc, o3d.geometry.PointCloud)
    assert len(lk.from_open3d(pc)) == sphere.n_vertices
