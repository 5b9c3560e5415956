"""Figures of the paper, drawn headless with matplotlib (Agg backend).

- `convergence_figure`: Figure 7, log10(E_k/E_0) against the iteration k, one
  labelled line per method.
- `interpolation_figure`: Figure 3, four shaded panels seen by the same camera:
  (a) the given mesh, (b) its limit surface (it shrinks away from the given
  vertices, drawn red), (c) the control mesh found by SOR-PIA with the given
  vertices red and the new control vertices blue, (d) the limit surface of
  that control mesh, passing through the red points. Triangles, quads and
  other polygons are drawn as they are (flat shaded, so that sharp creases
  show as sharp); crease edges and their limit curves (`crease_curves`) are
  drawn in orange.

matplotlib is an optional dependency (the ``plot`` extra); this
module imports it only when a figure is drawn, and `require_matplotlib` says
what to install when it is missing. Functions return a
``matplotlib.figure.Figure``; the caller saves it (``fig.savefig``) and closes
it (``matplotlib.pyplot.close(fig)`` is not needed: the figures are not
registered with pyplot).
"""

from __future__ import annotations

import math

import numpy as np

from ._meshinfo import boundary_share
from .errors import ParameterError
from .surface import edge_uv

# Faces drawn per panel at most: matplotlib sorts and paints each polygon in
# Python, so the time to draw a figure grows with the faces drawn.
FACE_BUDGET = 60_000
# Vertex markers drawn per panel at most (more only paint the panel red).
POINT_BUDGET = 4_000

GIVEN_COLOR = "#d62728"    # red: the given vertices V0 (paper Figure 3)
CONTROL_COLOR = "#1f4fd6"  # blue: the control vertices found by SOR-PIA
MESH_COLOR = np.array([0.80, 0.80, 0.78])
SURFACE_COLOR = np.array([0.62, 0.74, 0.90])
CREASE_COLOR = "#ff7f0e"   # orange: crease edges of the meshes, crease curves of the limit surfaces


def require_matplotlib() -> None:
    """Raise ImportError with what to install when matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("drawing figures needs matplotlib (sorpia's optional 'plot' extra): "
                          "pip install matplotlib") from None


def _new_figure(width_px: int, height_px: int, dpi: int = 100):
    # A Figure not registered with pyplot: no global state, no backend choice
    # needed, garbage-collected like any object; the Agg canvas draws it.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def convergence_figure(curves, tol: float | None = None, title: str | None = None,
                       size: tuple[int, int] = (900, 560)):
    """The paper's Figure 7: log10(E_k/E_0) against the iteration k.

    Parameters
    ----------
    curves : iterable of (label, errors)
        `errors[k]` = E_k/E_0 for k = 0..iterations (errors[0] = 1), one line
        per entry. Zeros (an exact solve) are drawn at the smallest positive
        float instead of -inf.
    tol : float, optional
        Drawn as a dashed horizontal line at log10(tol).
    size : (width, height) in pixels of the saved PNG (at the figure's dpi).
    """
    fig = _new_figure(*size)
    ax = fig.add_subplot(1, 1, 1)
    markers = "osD^vP*Xh<>"
    styles = ("-", "--", "-.", ":")  # methods with equal errors (GS and SOR at omega 1) stay distinguishable
    for j, (label, errors) in enumerate(curves):
        e = np.maximum(np.asarray(errors, dtype=float), np.finfo(float).tiny)
        k = np.arange(len(e))
        ax.plot(k, np.log10(e), marker=markers[j % len(markers)], markersize=3.5, linestyle=styles[j % len(styles)],
                markevery=max(1, len(e) // 25), linewidth=1.4, label=label)
    if tol is not None:
        ax.axhline(math.log10(tol), color="0.4", linestyle="--", linewidth=0.9, label=f"tol = {tol:g}")
    ax.set_xlabel("iteration k")
    ax.set_ylabel("log10(E_k / E_0)")
    ax.set_title(title or "Convergence of the PIA family (paper Figure 7)")
    ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.legend(loc="upper right", fontsize=9)
    ax.set_xlim(left=0)
    fig.tight_layout()
    return fig


def level_for_budget(n_faces: int, level: int, face_budget: int = FACE_BUDGET, *,
                     first_level_faces: int | None = None) -> int:
    """The largest refinement level <= `level` whose tessellation fits in
    `face_budget` faces; 0 at least. Loop: n_faces * 4**level triangles;
    Catmull-Clark: pass `first_level_faces` (the faces' vertex counts summed,
    the quads of level 1), giving first_level_faces * 4**(level - 1) quads."""
    def faces(k):
        if first_level_faces is None or k == 0:
            return n_faces * 4 ** k
        return first_level_faces * 4 ** (k - 1)

    while level > 0 and faces(level) > face_budget:
        level -= 1
    return level


def _view_vector(elev: float, azim: float) -> np.ndarray:
    """Unit vector from the scene towards matplotlib's camera at (elev, azim)."""
    e, a = math.radians(elev), math.radians(azim)
    return np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])


class _Faces:
    """Faces of any sizes for drawing: an (m, k) index array, or the counts +
    indices of sorpia.Polygons (kept as an (m, k) array when every face has k
    vertices)."""

    def __init__(self, faces):
        self.array = None
        if hasattr(faces, "face_vertex_counts"):
            counts = np.asarray(faces.face_vertex_counts, dtype=np.int64)
            indices = np.asarray(faces.face_vertex_indices, dtype=np.int64)
            if len(counts) and (counts == counts[0]).all():
                self.array = indices.reshape(len(counts), int(counts[0]))
            else:
                self.counts, self.indices = counts, indices
                self.starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        else:
            self.array = np.asarray(faces, dtype=np.int64)

    def __len__(self) -> int:
        return len(self.array) if self.array is not None else len(self.counts)

    def fan(self):
        """(triangles (t, 3), owner (t,)): each face split into the fan from its
        first vertex, and the face each triangle comes from."""
        if self.array is not None:
            m, k = self.array.shape
            tris = np.concatenate([self.array[:, [0, j, j + 1]] for j in range(1, k - 1)]) if k > 2 else \
                np.zeros((0, 3), np.int64)
            return tris, np.tile(np.arange(m), max(k - 2, 0))
        per_face = np.maximum(self.counts - 2, 0)
        owner = np.repeat(np.arange(len(self.counts)), per_face)
        j = np.arange(len(owner)) - (np.cumsum(per_face) - per_face)[owner] + 1  # 1..k-2 within each face
        first = self.starts[owner]
        return np.column_stack([self.indices[first], self.indices[first + j], self.indices[first + j + 1]]), owner

    def normals(self, vertices) -> np.ndarray:
        """(m, 3) unnormalised normals of the faces, twice their vector areas:
        the sums of their fan triangles' `_face_normals`."""
        tris, owner = self.fan()
        tn = _face_normals(vertices, tris)
        if self.array is not None and len(tris) == len(self.array):
            return tn
        return np.column_stack([np.bincount(owner, weights=tn[:, c], minlength=len(self)) for c in range(3)])

    def polygons(self, vertices, keep):
        """The kept faces' corner positions, as Poly3DCollection takes them."""
        if self.array is not None:
            return vertices[self.array[keep]]
        return [vertices[self.indices[self.starts[f]:self.starts[f] + self.counts[f]]] for f in keep]

    def rows(self):
        """The faces as lists of vertex indices."""
        if self.array is not None:
            return self.array.tolist()
        return [self.indices[s:s + c].tolist() for s, c in zip(self.starts, self.counts)]

    def edge_sides(self, edges) -> np.ndarray:
        """(k, 2, 2) int: for each edge (a, b), the (face, corner j) of the
        faces whose corners j, j + 1 are (a, b) or (b, a), two per edge (the
        same twice on a boundary). Raises ParameterError for a pair that is
        not an edge."""
        edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        found: dict = {(min(a, b), max(a, b)): [] for a, b in edges.tolist()}
        for f, face in enumerate(self.rows()):
            for j, (a, b) in enumerate(zip(face, face[1:] + face[:1])):
                sides = found.get((min(a, b), max(a, b)))
                if sides is not None:
                    sides.append((f, j))
        out = np.zeros((len(edges), 2, 2), dtype=np.int64)
        for i, (a, b) in enumerate(edges.tolist()):
            sides = found[(min(a, b), max(a, b))]
            if not sides:
                raise ParameterError(f"creases[{i}] = [{a}, {b}] is not an edge of the mesh")
            out[i] = [sides[0], sides[-1]]
        return out


def crease_curves(surface, faces, edges, samples: int = 9, holes=None):
    """The limit curves of crease edges on a `sorpia.LimitSurface`, for
    `interpolation_figure`: (points (k, samples, 3), normals (k, samples, 2,
    3)), the unit normals of the surface on either side of the curve (the
    same twice on a boundary or beside a hole), evaluated by Bfr along each
    edge's parameter line (`sorpia.surface.edge_uv`). `holes`: the surface's
    hole faces, which have no surface: a side that is a hole takes the other
    side's values, and an edge both of whose faces are holes has no curve
    (NaN, which matplotlib leaves undrawn)."""
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    F = _Faces(faces)
    rows = F.rows()
    sides = F.edge_sides(edges)
    in_hole = np.isin(sides[:, :, 0], np.asarray(holes if holes is not None else [], dtype=np.int64))
    sides[in_hole[:, 0], 0] = sides[in_hole[:, 0], 1]
    sides[in_hole[:, 1], 1] = sides[in_hole[:, 1], 0]
    no_surface = in_hole.all(axis=1)
    t = np.linspace(0.0, 1.0, samples)
    ids, uv = [], []
    for k, (side_a, side_b) in enumerate(sides.tolist()):
        for s, (f, j) in enumerate((side_a, side_b)):
            # Along the edge from its first vertex to its second: reversed on the side that runs b -> a.
            forward = rows[f][j] == edges[k][0]
            ids.append(np.full(samples, f))
            uv.append(edge_uv(surface.scheme, len(rows[f]), j, t if forward else t[::-1]))
    p = np.full((len(sides), 2, samples, 3), np.nan)
    n = np.full((len(sides), 2, samples, 3), np.nan)
    if not no_surface.all():
        keep = np.repeat(~no_surface, 2 * samples)
        p_kept, _, _, n_kept = surface.evaluate(np.concatenate(ids)[keep], np.concatenate(uv)[keep], derivatives=True)
        p[~no_surface] = p_kept.reshape(-1, 2, samples, 3)
        n[~no_surface] = n_kept.reshape(-1, 2, samples, 3)
    return p[:, 0], np.transpose(n, (0, 2, 1, 3))


def _face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted (unnormalised) face normals, (m, 3)."""
    t = vertices[faces]
    return np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])


def _vertex_normals(face_normals: np.ndarray, faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Unit vertex normals, (n_vertices, 3), from `_face_normals` of `faces`."""
    # Sums of the face normals at each corner by bincount (a vectorised
    # scatter-add, unlike np.add.at), corner 0 of every face first, then 1, then 2.
    corners = faces.T.ravel()
    vn = np.column_stack([np.bincount(corners, weights=np.tile(face_normals[:, c], 3), minlength=n_vertices)
                          for c in range(3)])
    norm = np.linalg.norm(vn, axis=1, keepdims=True)
    return vn / np.where(norm > 0, norm, 1.0)


def _boundary_share(faces: np.ndarray, n_vertices: int) -> float:
    """Boundary edges / edges: 0 for a closed mesh."""
    return boundary_share(faces, n_vertices)


def _visible_side(face_normals, view) -> float:
    """+1 when the camera looks at the outer side of most of the projected area
    (faces oriented outward), -1 when at the inner side (an open sheet seen
    from behind)."""
    n = face_normals @ view
    return 1.0 if n[n > 0].sum() >= -n[n < 0].sum() * 0.5 else -1.0


def _select_faces(face_normals, view, budget, side):
    """Indices of the faces to draw: all of them within the budget; beyond it
    the faces turned away from the camera go first (hidden on a closed mesh,
    seen through holes only on an open one), then an even stride."""
    keep = np.arange(len(face_normals))
    if len(keep) > budget:
        keep = keep[side * (face_normals @ view) > 0]
    if len(keep) > budget:
        keep = keep[:: math.ceil(len(keep) / budget)]
    return keep


def _shaded_colors(face_normals, base, light):
    norm = np.linalg.norm(face_normals, axis=1)
    n = face_normals / np.where(norm > 0, norm, 1.0)[:, None]
    # Two-sided Lambert shading: open meshes show their back side too.
    intensity = 0.30 + 0.70 * np.abs(n @ light)
    rgb = np.clip(base[None, :] * intensity[:, None], 0, 1)
    return np.column_stack([rgb, np.ones(len(rgb))])


def _crease_segments(points, normals, view, side, closed):
    """Segments (s, 2, 3) of polylines `points` (k, p, 3) to draw, with the
    unit normals (k, p, 2, 3) of the two sides: on a closed mesh only those
    with a side facing the camera at an end (matplotlib does not hide lines
    behind a surface); none where a point is NaN (no surface: crease_curves)."""
    seg = np.stack([points[:, :-1], points[:, 1:]], axis=2).reshape(-1, 2, 3)
    keep = np.isfinite(seg).all(axis=(1, 2))
    if closed:
        with np.errstate(invalid="ignore"):
            facing = (side * (normals @ view) > 0).any(axis=2)  # (k, p): a side faces the camera
        keep &= (facing[:, :-1] | facing[:, 1:]).ravel()
    return seg[keep]


def interpolation_figure(vertices, faces, given_surface, control_vertices, fitted_surface, *,
                         size: tuple[int, int] = (1200, 1000), elev: float = 30.0, azim: float = -60.0,
                         face_budget: int = FACE_BUDGET, point_budget: int = POINT_BUDGET,
                         title: str | None = None, iterations: int | None = None, level: int | None = None,
                         up: str = "z", scheme: str = "loop", creases=None, crease_curves=None, fair=None,
                         data_points=None, labels=None):
    """The paper's Figure 3 in four panels, the same camera in each; with
    `fair`, plain and fair interpolation side by side instead.

    Parameters
    ----------
    vertices : (n, 3) float64
        The given vertices V0 (drawn red).
    faces : (m, k) int array or sorpia.Polygons
        The given faces (also the faces of the control mesh): triangles,
        quads or any polygons, drawn as they are.
    given_surface : (V_s, F_s)
        Tessellated limit surface of the given mesh (panel b); F_s as `faces`.
    control_vertices : (n, 3) float64
        Control vertices found by SOR-PIA (drawn blue, panel c).
    fitted_surface : (V_s, F_s)
        Tessellated limit surface of the control mesh (panel d).
    size : (width, height) of the PNG in pixels (100 dpi).
    elev, azim : camera angles in degrees (matplotlib's view_init).
    face_budget, point_budget : most faces / markers drawn per panel; beyond
        them the faces turned away from the camera are left out, then an even
        stride of faces or markers is drawn (the panel title says so).
    up : {"x", "y", "z"}
        The axis drawn vertical (many mesh files have y up).
    scheme : {"loop", "catmull-clark"}
        Named in the titles.
    creases : (k, 2) int, optional
        Crease edges, drawn orange on the meshes (panels a and c).
    crease_curves : (given, fitted), optional
        Their limit curves on the two surfaces, each as `crease_curves`
        returns them, drawn orange on panels b and d.
    fair : (control_vertices, faces, (V_s, F_s), levels), optional
        A fair interpolation (`sorpia.fair_interpolate`): its fine control
        mesh (rows 0..n-1 the children of the given vertices) and its
        tessellated limit surface. The panels are then (a) the plain control
        mesh, (b) its limit surface, (c) the fair control mesh, (d) its limit
        surface, given vertices red; `given_surface` is not drawn and
        `crease_curves` only on panel b (the plain surface).
    data_points : (k, 3) float, optional
        Approximation's data (drawn red on panels b and d instead of the
        given vertices, at most `point_budget` of them, an even stride; the
        mesh panels then mark their own vertices blue).
    labels : four str, optional
        The panels' titles instead of Figure 3's.
    """
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    # A cyclic permutation of the axes (a rotation: orientation kept) puts `up` on z.
    axes = {"z": [0, 1, 2], "y": [2, 0, 1], "x": [1, 2, 0]}[up]
    V0 = np.asarray(vertices, dtype=float)[:, axes]
    F = _Faces(faces)
    Vc = np.asarray(control_vertices, dtype=float)[:, axes]
    Vg, Fg = np.asarray(given_surface[0], float)[:, axes], _Faces(given_surface[1])
    Vf, Ff = np.asarray(fitted_surface[0], float)[:, axes], _Faces(fitted_surface[1])

    view = _view_vector(elev, azim)
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(up, view)
    right = right / (np.linalg.norm(right) or 1.0)
    light = view + 0.5 * up - 0.4 * right  # from over the viewer's left shoulder
    light /= np.linalg.norm(light)

    # One box of axis limits around everything drawn, equal scale on the three
    # axes (box aspect = extents): the same camera in every panel.
    if fair is not None:
        Vfc, Ffc = np.asarray(fair[0], float)[:, axes], _Faces(fair[1])
        Vfs, Ffs = np.asarray(fair[2][0], float)[:, axes], _Faces(fair[2][1])
        Vg = np.zeros((0, 3))  # not drawn
    data = None if data_points is None else np.asarray(data_points, dtype=float)[:, axes]
    allpts = np.concatenate([V0, Vc, Vg, Vf] + ([Vfc, Vfs] if fair is not None else [])
                            + ([] if data is None else [data]))
    allpts = allpts[np.isfinite(allpts).all(axis=1)]
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    extent = np.maximum(hi - lo, 0.05 * max(float((hi - lo).max()), 1e-12))  # flat meshes keep some depth
    centre = (lo + hi) / 2

    # Face normals: of the given mesh once (side, markers, panel a), of each other surface once.
    normals0 = F.normals(V0)
    side = _visible_side(normals0, view)
    # Markers: on a (nearly) closed mesh only the vertices facing the camera
    # (matplotlib cannot hide points behind a surface); at most point_budget.
    # Nearly closed: boundary edges under 5% of the edges of the faces' fans
    # (OpenSubdiv's pawn and rook, open at the bottom, have 1.4% and 1.1%).
    fan, _ = F.fan()
    closed = _boundary_share(fan, len(V0)) < 0.05
    referenced = np.zeros(len(V0), bool)
    referenced[fan.ravel()] = True
    shown = np.flatnonzero(referenced)  # np.unique(F) in O(n), without sorting every index
    if closed:
        shown = shown[side * (_vertex_normals(_face_normals(V0, fan), fan, len(V0))[shown] @ view) > 0]
    stride = max(1, math.ceil(len(shown) / point_budget))
    shown = shown[::stride]
    marker = float(np.clip(3000.0 / max(len(shown), 1), 1.0, 14.0))
    if data is not None:
        data_stride = max(1, math.ceil(len(data) / point_budget))
        data = data[::data_stride]
        data_marker = float(np.clip(3000.0 / max(len(data), 1), 1.0, 14.0))

    # Crease lines: the mesh edges with the normals of their two faces, the
    # limit curves with the surface's normals on either side.
    lines = [None] * 4
    if creases is not None and len(creases):
        crease_edges = np.asarray(creases, dtype=np.int64).reshape(-1, 2)
        crease_faces = F.edge_sides(crease_edges)[:, :, 0]  # (k, 2)
        for j, V in ((0, V0), (2, Vc)):
            n = F.normals(V)[crease_faces]
            n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-300)
            lines[j] = _crease_segments(V[crease_edges], np.repeat(n[:, None], 2, axis=1), view, side, closed)
    if crease_curves is not None:
        for j, (points, normals) in ((1, crease_curves[0]), (3, crease_curves[1])):
            lines[j] = _crease_segments(np.asarray(points)[..., axes], np.asarray(normals)[..., axes], view, side,
                                        closed)

    # Magnify the box (matplotlib leaves wide margins) as far as its projection
    # fits the panel: matplotlib scales the box to its aspect / |aspect|; the
    # panels are about 0.86 * height / width as tall as they are wide.
    box = extent / np.linalg.norm(extent)
    screen_up = np.cross(view, right)
    fit = max(np.abs(box * right).sum(), np.abs(box * screen_up).sum() / (0.86 * size[1] / size[0]))
    zoom = min(1.35, 1.4 / fit)

    if fair is not None:  # panel by panel: the plain mesh's creases on (a), its curves on (b)
        lines = [lines[2], None if crease_curves is None else lines[3], None, None]
    fig = _new_figure(*size)
    name = {"loop": "Loop", "catmull-clark": "Catmull-Clark"}.get(scheme, scheme)
    given, control = (V0[shown], marker, GIVEN_COLOR), (Vc[shown], marker, CONTROL_COLOR)
    panels = [
        ("(a) given mesh", V0, F, MESH_COLOR, True, [given]),
        (f"(b) {name} limit surface of the given mesh", Vg, Fg, SURFACE_COLOR, False, [given]),
        ("(c) control mesh by SOR-PIA" + (f", {iterations} iterations" if iterations is not None else ""),
         Vc, F, MESH_COLOR, True, [control, given]),
        ("(d) limit surface of the control mesh", Vf, Ff, SURFACE_COLOR, False, [given]),
    ]
    if fair is not None:
        fine_control = (Vfc[:len(V0)][shown], marker, CONTROL_COLOR)
        panels = [
            ("(a) plain control mesh (SOR-PIA)" + (f", {iterations} iterations" if iterations is not None else ""),
             Vc, F, MESH_COLOR, True, [control, given]),
            ("(b) its limit surface: plain interpolation", Vf, Ff, SURFACE_COLOR, False, [given]),
            (f"(c) fair control mesh, {fair[3]} level{'s' if fair[3] > 1 else ''} finer", Vfc, Ffc, MESH_COLOR, True,
             [fine_control, given]),
            ("(d) its limit surface: fair interpolation", Vfs, Ffs, SURFACE_COLOR, False, [given]),
        ]
    if data is not None:
        marks = [(data, data_marker, GIVEN_COLOR)]
        panels = [(label, Vp, Fp, base, edges, marks if not edges else [(Vp[shown], marker, CONTROL_COLOR)])
                  for label, Vp, Fp, base, edges, _ in panels]
    if labels is not None:
        panels = [(label,) + panel[1:] for label, panel in zip(labels, panels)]
    for j, (label, Vp, Fp, base, edges, points) in enumerate(panels):
        ax = fig.add_subplot(2, 2, j + 1, projection="3d")
        ax.computed_zorder = False  # markers painted over the surface, not sorted with it
        normals = normals0 if Vp is V0 else Fp.normals(Vp)
        keep = _select_faces(normals, view, face_budget, side)
        edgecolor = "none"
        linewidth = 0.0
        if edges and len(keep) <= 20_000:
            edgecolor, linewidth = (0.15, 0.15, 0.15, 0.6), 0.5 if len(keep) <= 3_000 else 0.15
        coll = Poly3DCollection(Fp.polygons(Vp, keep), facecolors=_shaded_colors(normals[keep], base, light),
                                edgecolors=edgecolor, linewidths=linewidth)
        coll.set_zorder(1)
        ax.add_collection3d(coll)
        if lines[j] is not None and len(lines[j]):
            crease = Line3DCollection(lines[j], colors=CREASE_COLOR, linewidths=1.6)
            crease.set_zorder(1.5)
            ax.add_collection3d(crease)
        for z, (P, size, color) in enumerate(points):
            ax.scatter(P[:, 0], P[:, 1], P[:, 2], s=size, c=color, depthshade=False, linewidths=0, zorder=2 + z)
        if len(keep) < len(Fp):
            label += f"\n({len(keep)} of {len(Fp)} faces drawn)"
        ax.set_title(label, fontsize=10)
        ax.set_xlim(centre[0] - extent[0] / 2, centre[0] + extent[0] / 2)
        ax.set_ylim(centre[1] - extent[1] / 2, centre[1] + extent[1] / 2)
        ax.set_zlim(centre[2] - extent[2] / 2, centre[2] + extent[2] / 2)
        ax.set_proj_type("ortho")
        ax.view_init(elev=elev, azim=azim)
        try:
            ax.set_box_aspect(tuple(extent), zoom=zoom)
        except TypeError:  # matplotlib < 3.7 has no zoom
            ax.set_box_aspect(tuple(extent))
        ax.set_axis_off()
    note = []
    if level is not None:
        note.append(f"limit surfaces at refinement level {level}")
    if stride > 1:
        note.append(f"every {stride}th vertex marked")
    if closed:
        note.append("vertices facing the camera marked")
    if crease_curves is not None or creases is not None:
        note.append("creases orange")
    fig.suptitle((title or f"{name} limit surface and SOR-PIA interpolation (paper Figure 3)")
                 + ("\n" + ", ".join(note) if note else ""), fontsize=11)
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.90, wspace=0.02, hspace=0.12)
    return fig
