"""plotting.interpolation_figure with quads, mixed polygons and creases, and
plotting.crease_curves against the limit surface."""

from __future__ import annotations

import io

import numpy as np
import pytest

import sorpia
from sorpia import _plotting as plotting

pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")


def orange_pixels(fig) -> int:
    from matplotlib.image import imread

    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    buf.seek(0)
    rgb = imread(buf)[..., :3]
    # CREASE_COLOR #ff7f0e = (1.0, 0.50, 0.05)
    return int(((rgb[..., 0] > 0.9) & (np.abs(rgb[..., 1] - 0.5) < 0.12) & (rgb[..., 2] < 0.2)).sum())


def test_polygon_normals_are_twice_the_vector_areas_of_the_faces():
    # Shoelace: a planar polygon's vector area is its area times its unit
    # normal; the normals are twice that (sums of fan-triangle cross products). A square of side 2 (area 4), a regular hexagon of side 1 (area
    # 3 sqrt(3) / 2) and a triangle, in the plane z = 0, counter-clockwise.
    hexagon = [[np.cos(a), np.sin(a), 0.0] for a in np.arange(6) * np.pi / 3]
    v = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [3, 0, 0]] + hexagon, dtype=float)
    polys = sorpia.Polygons(np.array([4, 6, 3]), np.array([0, 1, 2, 3, 5, 6, 7, 8, 9, 10, 1, 4, 2]))
    n = plotting._Faces(polys).normals(v)
    assert np.allclose(n, [[0, 0, 8], [0, 0, 3 * np.sqrt(3)], [0, 0, 2]], atol=1e-14)
    # Equal sizes take the array path and give the same.
    quads = sorpia.Polygons(np.array([4, 4]), np.array([0, 1, 2, 3, 3, 2, 1, 0]))
    assert np.allclose(plotting._Faces(quads).normals(v), [[0, 0, 8], [0, 0, -8]])


def test_crease_curves_run_from_limit_point_to_limit_point_on_both_sides():
    # The curve of edge (a, b) starts at a's limit position and ends at b's,
    # whichever face it is evaluated from; the normals are unit vectors.
    v, f = sorpia.shapes.grid(6, 6)
    v = np.asarray(v)
    edges = np.array([[7, 8], [8, 14], [14, 7], [0, 1]])
    edges = np.array([e for e in edges if any(set(e) <= set(face) for face in np.asarray(f).tolist())])
    for scheme in ("loop", "catmull-clark"):
        s = sorpia.LimitSurface(v, f, scheme=scheme, creases=(edges, np.inf))
        limit = s.tessellate(1)[0]
        points, normals = plotting.crease_curves(s, f, edges, samples=5)
        assert points.shape == (len(edges), 5, 3) and normals.shape == (len(edges), 5, 2, 3)
        assert np.abs(points[:, 0] - limit[edges[:, 0]]).max() <= 1e-13
        assert np.abs(points[:, -1] - limit[edges[:, 1]]).max() <= 1e-13
        assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0)
    with pytest.raises(sorpia.ParameterError, match=r"creases\[0\] = \[0, 35\] is not an edge"):
        plotting.crease_curves(s, f, [[0, 35]])


@pytest.mark.parametrize("polygons", [False, True])
def test_quads_and_polygons_are_drawn_with_their_creases(polygons):
    # A Catmull-Clark tessellation of a triangle mesh is a quad mesh: draw it
    # as the given mesh (quads, or sorpia.Polygons), creases and their curves
    # in orange; without creases no orange at all.
    v, f = sorpia.shapes.grid(5, 5)
    v, quads = sorpia.limit_surface(v, f, 1, scheme="catmull-clark")
    faces = sorpia.Polygons(np.full(len(quads), 4), quads.ravel()) if polygons else quads
    v = v + [0, 0, 0.3] * np.abs(v[:, [0]] - 0.5)
    edges = np.array([[a, b] for a, b in zip(quads[:, 0], quads[:, 1])][:6])
    kwargs = dict(size=(500, 400), scheme="catmull-clark", level=1)
    plain = plotting.interpolation_figure(v, faces, (v, faces), v, (v, faces), **kwargs)
    assert orange_pixels(plain) == 0
    curves = (v[edges], np.zeros((len(edges), 2, 2, 3)) + [0, 0, 1])  # straight, normals up
    marked = plotting.interpolation_figure(v, faces, (v, faces), v, (v, faces), creases=edges,
                                           crease_curves=(curves, curves), **kwargs)
    assert orange_pixels(marked) > 100
