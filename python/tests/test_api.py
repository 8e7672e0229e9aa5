"""The numpy API: meshes in and out, simplify, LOD chains, compare, files."""
import threading

import numpy as np
import pytest

import pylodkit as lk


def test_simplify_reaches_target_and_keeps_attributes(sphere):
    lod, report = lk.simplify(sphere, target=500)
    assert 497 <= lod.n_faces <= 500
    assert report["triangles"] == lod.n_faces
    assert report["input_triangles"] == sphere.n_faces
    assert report["stop"] == "reached the target"
    assert lod.vertices.dtype == np.float32 and lod.vertices.shape[1] == 3
    assert lod.faces.dtype == np.uint32 and lod.faces.max() < lod.n_vertices
    assert lod.normals is not None and lod.colors is not None and lod.colors.dtype == np.uint8


def test_simplify_ratio_and_max_error(blob):
    half, r = lk.simplify(blob, ratio=0.5)
    assert half.n_faces <= blob.n_faces // 2
    tight, r2 = lk.simplify(blob, ratio=0.0, max_error=1e-4)
    assert r2["stop"].startswith("stopped short") and tight.n_faces > 0


def test_simplify_is_deterministic_and_matches_dtypes(blob):
    a, _ = lk.simplify(blob, ratio=0.1)
    b, _ = lk.simplify(lk.Mesh(blob.vertices.astype(np.float64), blob.faces.astype(np.int64)), ratio=0.1)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


def test_non_contiguous_input_is_read(blob):
    v = np.asfortranarray(blob.vertices)
    wide = np.zeros((blob.n_faces, 6), np.int32)
    wide[:, ::2] = blob.faces
    f = wide[:, ::2]  # a strided view
    assert not v.flags.c_contiguous and not f.flags.c_contiguous
    a, _ = lk.simplify(lk.Mesh(v, f), ratio=0.2)
    b, _ = lk.simplify(blob, ratio=0.2)
    assert np.array_equal(a.faces, b.faces)


def test_lock_border_keeps_border_vertices():
    # An open grid: its rim must not move.
    n = 20
    xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    v = np.stack([xs.ravel(), ys.ravel(), np.sin(xs.ravel() * 3) * 0.1], axis=1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    f = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    lod, _ = lk.simplify(lk.Mesh(v, f), ratio=0.2, lock_border=True)
    rim = {tuple(p) for p in v[(v[:, 0] == 0) | (v[:, 0] == 1) | (v[:, 1] == 0) | (v[:, 1] == 1)].astype(np.float32)}
    kept = {tuple(p) for p in lod.vertices}
    assert rim <= kept


def test_lod_chain_levels_and_measure(sphere):
    chain = lk.lod_chain(sphere, levels=3)
    faces = [r["triangles"] for _, r in chain]
    assert faces[0] <= 2560 and faces[1] <= 1280 and faces[2] <= 640
    assert [r["level"] for _, r in chain] == [1, 2, 3]
    means = [r["measured_mean_error"] for _, r in chain]
    assert all(m is not None and m > 0 for m in means) and means == sorted(means)
    fast = lk.lod_chain(sphere, ratios=[0.3], measure=False)
    assert fast[0][1]["measured_mean_error"] is None


def test_lod_chain_refuses_ratios_that_do_not_fall(sphere):
    for ratios in ([0.2, 0.5], [0.5, 0.5], [0.5, 0.25, 0.3]):
        with pytest.raises(lk.OptionError, match="smaller than the one before"):
            lk.lod_chain(sphere, ratios=ratios)


def test_a_chain_that_stalls_ends_at_its_last_new_level():
    # 80 faces halved ten times: the smallest closed mesh comes first.
    chain = lk.lod_chain(lk.icosphere(1), levels=10, measure=False)
    faces = [r["triangles"] for _, r in chain]
    assert 1 <= len(chain) < 10 and all(b < a for a, b in zip(faces, faces[1:])), faces
    assert [r["chain_end"] for _, r in chain[:-1]] == [None] * (len(chain) - 1)
    assert chain[-1][1]["chain_end"].startswith("stopped short"), chain[-1][1]


def test_mesh_and_point_cloud_check_their_arrays_when_made():
    v = np.zeros((4, 3), np.float32)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    cases = [
        (lambda: lk.Mesh(v, f.astype(np.float64)), "faces: expected an int32, int64, uint32 or uint64"),
        (lambda: lk.Mesh(v[:, :2], f), r"vertices: expected shape \(n, 3\), got \(4, 2\)"),
        (lambda: lk.Mesh(v[0], f), r"vertices: expected shape \(n, 3\), got shape \(3,\)"),
        (lambda: lk.Mesh(v.astype(np.int64), f), "vertices: expected a float32 or float64 array"),
        (lambda: lk.Mesh(v, f[:, :2]), "faces: "),
        (lambda: lk.Mesh(v, f, colors=np.zeros((3, 4), np.uint8)), "colors: has 3 rows but the mesh has 4 vertices"),
        (lambda: lk.Mesh(v, f, colors=np.zeros((4, 4), np.int32)), "colors: expected a uint8 array"),
        (lambda: lk.Mesh(v, f, normals=np.zeros((4, 2))), "normals: "),
        (lambda: lk.Mesh(v, f, uvs=np.zeros((4, 3))), "uvs: "),
        (lambda: lk.PointCloud(np.zeros((5, 2))), "points: "),
        (lambda: lk.PointCloud(np.zeros((5, 3)), colors=np.zeros((4, 3))), "colors: has 4 rows but the cloud has 5 points"),
    ]
    for make, msg in cases:
        with pytest.raises(lk.InputError, match=msg):
            make()
        with pytest.raises(ValueError):
            make()
    # What is right is kept as given; no faces may be an empty list.
    m = lk.Mesh(v, f, colors=np.zeros((4, 3)), uvs=np.zeros((4, 2), np.float32))
    assert m.faces is f or np.shares_memory(m.faces, f)
    assert lk.Mesh(v, []).n_faces == 0


def test_compare_has_the_cli_json_keys(sphere):
    coarse, _ = lk.simplify(sphere, ratio=0.1)
    r = lk.compare(sphere, coarse, samples=20_000)
    assert set(r) == {"a_to_b", "b_to_a", "symmetric", "samples_per_kind", "seed"}
    assert set(r["a_to_b"]) == {"samples", "vertex_samples", "edge_samples", "face_samples", "min",
                                "max", "mean", "rms", "max_at", "diagonal", "max_pct", "mean_pct", "rms_pct"}
    assert set(r["symmetric"]) == {"samples", "max", "mean", "rms", "diagonal", "max_pct",
                                   "mean_pct", "rms_pct"}
    assert r["samples_per_kind"] == 20_000 and r["seed"] == 1998
    assert 0 < r["symmetric"]["mean"] <= r["symmetric"]["max"]
    assert lk.compare(sphere, coarse, samples=20_000) == r
    same = lk.compare(sphere, sphere, samples=10_000)
    assert same["symmetric"]["max"] < 1e-6 * same["symmetric"]["diagonal"]


def test_load_save_round_trip(tmp_path, sphere):
    for ext in ("ply", "obj", "glb"):
        p = tmp_path / ("s." + ext)
        lk.save(sphere, p)
        back = lk.load(p)
        assert isinstance(back, lk.Mesh) and back.n_faces == sphere.n_faces
    lk.save(sphere, tmp_path / "a.ply", ascii=True)
    assert (tmp_path / "a.ply").read_bytes().startswith(b"ply\nformat ascii")
    # Deterministic: the same mesh gives the same bytes.
    lk.save(sphere, tmp_path / "b.ply")
    lk.save(sphere, tmp_path / "c.ply")
    assert (tmp_path / "b.ply").read_bytes() == (tmp_path / "c.ply").read_bytes()


def test_points_round_trip(tmp_path):
    pts = np.random.default_rng(1).normal(size=(500, 3)).astype(np.float32)
    lk.save(lk.PointCloud(pts), tmp_path / "p.xyz")
    back = lk.load(tmp_path / "p.xyz")
    assert isinstance(back, lk.PointCloud) and len(back) == 500
    assert np.allclose(back.points, pts, atol=1e-5)


def test_bunny_is_built_in():
    b = lk.bunny()
    assert (b.n_vertices, b.n_faces) == (35947, 69451)


def test_gil_is_released_during_simplify(blob):
    # A Python thread keeps counting while simplify runs in another.
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)

    t = threading.Thread(target=count)
    t.start()
    try:
        for _ in range(3):
            lk.simplify(blob, ratio=0.05)
    finally:
        stop.set()
        t.join()
    assert len(ticks) > 1000


def test_parallel_threads_give_the_same_result(blob):
    out = [None] * 4

    def run(i):
        out[i] = lk.simplify(blob, ratio=0.1)[0].faces

    ts = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert all(np.array_equal(out[0], o) for o in out[1:])
