"""limit_points and limit_matrix against the closed-form Loop masks."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse

import sorpia


def test_version_is_the_package_version():
    from importlib.metadata import version

    assert sorpia.__version__ == version("sorpia")


def test_test_meshes_cover_valences_3_to_12_and_a_pole(mesh):
    # Guards the premise of the tests below: the meshes really stress what they say.
    name, v, f = mesh
    valence = np.bincount(np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1),
                                    axis=0).ravel(), minlength=len(v))
    if name == "sphere-hull":
        assert valence.min() <= 4 and valence.max() >= 9
    if name == "irregular-torus":
        assert valence.min() == 3 and valence.max() >= 10
    if name == "pole-48":
        assert valence.max() == 48


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_limit_matrix_equals_closed_form(mesh, boundary, closed_form):
    # 1e-14: both sides evaluate the same closed forms in double precision.
    _, v, f = mesh
    b = sorpia.limit_matrix(f, len(v), boundary=boundary)
    assert isinstance(b, scipy.sparse.csr_matrix) and b.shape == (len(v), len(v))
    expected = closed_form(f, len(v), boundary)
    assert abs(b - expected).max() <= 1e-14
    assert np.array_equal(b.nonzero()[0], expected.nonzero()[0])  # same sparsity: no stray entries


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_limit_points_equal_closed_form_masks(mesh, boundary, closed_form):
    # 1e-14 relative to the coordinates' size (all test meshes fit in [-2, 2]^3).
    _, v, f = mesh
    lp = sorpia.limit_points(v, f, boundary=boundary)
    assert lp.shape == v.shape and lp.dtype == np.float64
    assert np.abs(lp - closed_form(f, len(v), boundary) @ v).max() <= 1e-14


def test_limit_points_shrink_a_sphere():
    # Loop surfaces shrink: every limit point of an icosphere lies inside the unit sphere.
    v, f = sorpia.shapes.icosphere(2)
    r = np.linalg.norm(sorpia.limit_points(v, f), axis=1)
    assert (r < 1 - 1e-3).all()


def test_unreferenced_vertex_passes_through_with_a_warning():
    v, f = sorpia.shapes.icosphere(1)
    v = np.vstack([v, [[3.0, 4.0, 5.0]]])
    with pytest.warns(sorpia.UnreferencedVerticesWarning, match="1 of 43 vertices"):
        lp = sorpia.limit_points(v, f)
    assert np.array_equal(lp[-1], v[-1])


def test_int64_and_float32_input_is_converted():
    v, f = sorpia.shapes.icosphere(1)
    exact = sorpia.limit_points(v, f)
    lp = sorpia.limit_points(v.astype(np.float32), f.astype(np.int64))
    assert np.abs(lp - exact).max() < 1e-6  # float32 input carries ~6e-8 relative error


def test_unknown_boundary_is_refused():
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(ValueError, match="unknown boundary 'smooth'"):
        sorpia.limit_points(v, f, boundary="smooth")


def test_out_of_range_face_is_named():
    v, f = sorpia.shapes.icosphere(0)
    f = f.copy()
    f[7, 1] = 99
    with pytest.raises(sorpia.MeshError, match=r"faces\[7\]"):
        sorpia.limit_points(v, f)
