"""``sorpia demo``: every capability (interpolation, fair interpolation, approximation) on a built-in sample mesh."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__, decimate, read_mesh, shapes, write_mesh
from .approximate import run_approximate
from .common import UserError, require_plotting
from .compare import run_compare
from .fit import run_fit
from .render import run_render

# The demo's cage for approximation: the sample decimated to this many vertices.
CAGE_VERTICES = 120


def sample_mesh(scheme: str = "loop"):
    """The demo's mesh. Loop: a closed genus-1 mesh of 400 vertices with
    random edge flips (sorpia.shapes.irregular: valences 3 to 12, most
    vertices extraordinary); Catmull-Clark: a torus of 24 x 12 quads. Either
    with its tube made wavy so that the limit surface visibly shrinks away
    from the vertices. Returns (vertices (n, 3) float64, faces (m, 3) or
    (m, 4) int32)."""
    if scheme == "catmull-clark":
        V, F = _quad_torus(24, 12)
    else:
        V, F = shapes.irregular(400, seed=3)
    V = np.array(V, dtype=float)
    # A bump in the tube radius, 5 waves around the ring: the Loop surface
    # shrinks most at the crests, where the curvature is largest.
    angle = np.arctan2(V[:, 1], V[:, 0])
    ring = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(len(V))])
    offset = V - ring  # from the tube's centre circle (major radius 1)
    V = ring + offset * (1.0 + 0.45 * np.sin(5 * angle))[:, None]
    return V, F


def _quad_torus(nu: int, nv: int):
    """A torus of nu x nv quads, radii 1 and 0.4, faces counter-clockwise seen from outside."""
    u, v = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv, indexing="ij")
    r = 1.0 + 0.4 * np.cos(v)
    V = np.column_stack([(r * np.cos(u)).ravel(), (r * np.sin(u)).ravel(), (0.4 * np.sin(v)).ravel()])
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, ((i + 1) % nu) * nv + j
    c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
    F = np.column_stack([a.ravel(), b.ravel(), c.ravel(), d.ravel()]).astype(np.int32)
    return V, F


def _new_demo_folder() -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for k in range(100):
        folder = Path(f"sorpia-demo-{stamp}" + (f"-{k}" if k else ""))  # relative: short paths in the summary
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            continue
    raise UserError("could not create a new sorpia-demo-* folder in the working directory")


def run_demo(out_dir=None, *, quiet=False, scheme="auto", out=None) -> int:
    """`sorpia demo`: every capability on the built-in sample mesh of the
    scheme (auto: Loop's): interpolation (fit, compare, render), fair
    interpolation (fit --fair, render --fair) and approximation (a cage
    decimated from the sample, fitted to the points of the fitted limit
    surface: approximate, render --cage), each with its picture where
    matplotlib is installed."""
    out = out if out is not None else sys.stdout
    t_start = time.perf_counter()
    if out_dir is None:
        folder = _new_demo_folder()
    else:
        folder = Path(out_dir)
        if folder.exists() and not folder.is_dir():
            raise UserError(f"--out {folder} is a file, not a folder")
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(f"--out {folder}: cannot create the folder: {exc.strerror}") from None
    try:
        plots = True
        require_plotting()
    except UserError as exc:
        plots = False
        print(f"sorpia demo: no figures: {exc}", file=out)
    paths = {
        "sample mesh": folder / "sample.obj",
        "control mesh": folder / "control.obj",
        "limit surface of the control mesh": folder / "surface.obj",
        "fit report": folder / "fit-report.json",
        "Table 1 (Markdown)": folder / "table.md",
        "Table 1 (CSV)": folder / "table.csv",
        "comparison (JSON)": folder / "compare.json",
        "fair control mesh (one level finer)": folder / "fair.obj",
        "fair interpolation report": folder / "fair-report.json",
        f"cage ({CAGE_VERTICES} vertices, decimated)": folder / "cage.obj",
        "cage fitted to the surface's points": folder / "approximation.obj",
        "approximation report": folder / "approximation-report.json",
    }
    if plots:
        paths["Figure 7 (convergence)"] = folder / "convergence.png"
        paths["Figure 3 (interpolation)"] = folder / "figure3.png"
        paths["plain and fair interpolation"] = folder / "fair.png"
        paths["approximation"] = folder / "approximation.png"
    scheme = "loop" if scheme == "auto" else scheme
    V, F = sample_mesh(scheme)
    write_mesh(paths["sample mesh"], V, F)
    sample = paths["sample mesh"]
    say = (lambda *a: None) if quiet else (lambda *a: print(*a, file=out))
    what = "a wavy torus of quads" if scheme == "catmull-clark" else "a wavy torus with random edge flips"
    say(f"sorpia {__version__} demo: sample mesh {sample} ({what})\n")
    codes = []

    def step(run, *args, **kwargs):
        code, _ = run(*args, quiet=quiet, out=out, **kwargs)
        codes.append(code)
        say("")

    # Interpolation: the control mesh, every method, Figure 3.
    step(run_fit, sample, paths["control mesh"], surface=paths["limit surface of the control mesh"], level=3,
         report=paths["fit report"], scheme=scheme)
    step(run_compare, sample, table=paths["Table 1 (Markdown)"], csv_path=paths["Table 1 (CSV)"],
         json_path=paths["comparison (JSON)"], plot=paths.get("Figure 7 (convergence)"), scheme=scheme)
    if plots:
        step(run_render, sample, paths["Figure 3 (interpolation)"], scheme=scheme)
    # Fair interpolation: a control mesh one level finer through the same vertices, bending least.
    step(run_fit, sample, paths["fair control mesh (one level finer)"], fair=True,
         report=paths["fair interpolation report"], scheme=scheme)
    if plots:
        step(run_render, sample, paths["plain and fair interpolation"], fair=True, scheme=scheme)
    # Approximation: a light cage (the sample decimated; its triangles paired into quads for Catmull-Clark)
    # fitted to the points of the limit surface written above.
    Vt, Ft = read_mesh(sample, triangulate=True)
    cage = decimate(Vt, Ft, CAGE_VERTICES, scheme=scheme, strict=False)
    cage_path = paths[f"cage ({CAGE_VERTICES} vertices, decimated)"]
    write_mesh(cage_path, cage.vertices, cage.faces)
    data = paths["limit surface of the control mesh"]
    step(run_approximate, data, paths["cage fitted to the surface's points"], cage=cage_path,
         report=paths["approximation report"], scheme=scheme)
    if plots:
        step(run_render, data, paths["approximation"], cage=cage_path, scheme=scheme)
    width = max(len(k) for k in paths)
    say(f"sorpia demo: done in {time.perf_counter() - t_start:.1f} s; files in {folder}:")
    for what, p in paths.items():
        say(f"  {what:<{width}}  {p}")
    say(f"next: sorpia info {sample}   |   sorpia fit --help")
    return max(codes)
