"""Small meshes the tests make (no data outside the repository)."""
import numpy as np
import pytest

import pylodkit as lk


@pytest.fixture(scope="session")
def sphere():
    """An icosphere of 5,120 faces with per-vertex colours and normals."""
    m = lk.icosphere(4)
    v = m.vertices
    colors = np.concatenate([((v * 0.5 + 0.5) * 255).astype(np.uint8),
                             np.full((len(v), 1), 255, np.uint8)], axis=1)
    return lk.Mesh(m.vertices, m.faces, normals=v.copy(), colors=colors)


@pytest.fixture(scope="session")
def blob():
    """A closed noisy sphere of about 20k faces."""
    return lk.blob(20_000)
