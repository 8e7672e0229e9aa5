"""Errors are pylodkit exceptions with the CLI's one-line messages."""
import numpy as np
import pytest

import pylodkit as lk


def test_bad_index_is_an_input_error():
    m = lk.Mesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 5]]))
    with pytest.raises(lk.InputError, match="face 0 has vertex index 5 but the mesh has 3 vertices"):
        lk.simplify(m, ratio=0.5)
    with pytest.raises(ValueError):
        lk.compare(m, m)


def test_negative_index_and_shapes():
    with pytest.raises(lk.InputError, match="vertex index -1"):
        lk.simplify(lk.Mesh(np.zeros((3, 3)), np.array([[0, 1, -1]])), ratio=0.5)
    with pytest.raises(lk.InputError, match=r"vertices: expected shape \(n, 3\), got \(3, 2\)"):
        lk.simplify(lk.Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]])), ratio=0.5)
    with pytest.raises(lk.InputError, match="vertices: expected a float32 or float64 array"):
        lk.simplify(lk.Mesh(np.zeros((3, 3), np.int32), np.array([[0, 1, 2]])), ratio=0.5)
    with pytest.raises(lk.InputError, match="colors: has 2 rows but the mesh has 3 vertices"):
        lk.simplify(lk.Mesh(np.zeros((3, 3)), [[0, 1, 2]], colors=np.zeros((2, 4), np.uint8)), ratio=0.5)
    with pytest.raises(lk.InputError, match="expected a mesh"):
        lk.simplify(42, ratio=0.5)


def test_non_finite_vertex():
    v = np.zeros((3, 3))
    v[1, 0] = np.nan
    with pytest.raises(lk.InputError, match="vertex 1 has a non-finite coordinate"):
        lk.simplify(lk.Mesh(v, [[0, 1, 2]]), ratio=0.5)


def test_option_ranges_name_the_range(sphere):
    with pytest.raises(lk.OptionError, match=r"ratio=1.5: expected a number in \[0, 1\]"):
        lk.simplify(sphere, ratio=1.5)
    with pytest.raises(lk.OptionError, match=r"heap_size=0: expected an integer in 1..=16777216"):
        lk.simplify(sphere, ratio=0.5, heap_size=0)
    with pytest.raises(lk.OptionError, match="give target=FACES, ratio=R or max_error=E"):
        lk.simplify(sphere)
    with pytest.raises(lk.OptionError, match="conflict"):
        lk.simplify(sphere, 10, ratio=0.5)
    with pytest.raises(lk.OptionError, match=r"levels=0: expected an integer in 1..=32"):
        lk.lod_chain(sphere, levels=0)
    with pytest.raises(lk.OptionError, match=r"samples=0"):
        lk.compare(sphere, sphere, samples=0)
    with pytest.raises(ValueError):
        lk.simplify(sphere, ratio=float("nan"))


def test_file_errors(tmp_path):
    with pytest.raises(lk.FileError) as e:
        lk.load(tmp_path / "missing.ply")
    assert isinstance(e.value, OSError) and "missing.ply" in str(e.value)
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999\nend_header\n")
    with pytest.raises(lk.InputError) as e:
        lk.load(bad)
    assert str(e.value).startswith(str(bad)) and "\n" not in str(e.value)
    with pytest.raises(lk.InputError, match="unknown file extension"):
        lk.load(tmp_path / "x.abc")
    with pytest.raises(lk.InputError, match="unknown output extension"):
        lk.save(lk.icosphere(1), tmp_path / "x.abc")
    assert issubclass(lk.InputError, lk.LodkitError) and issubclass(lk.FileError, lk.LodkitError)
