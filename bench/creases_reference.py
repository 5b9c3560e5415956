"""B with sharpness tags against OpenSubdiv's refinement of the whole mesh,
on OpenSubdiv's tagged shapes where that refinement fits in memory.

For each shape (its own tags, read with read_mesh(tags=True)): sorpia's B
(sorpia.limit_matrix: rows from the faces around each vertex) and the
reference (sorpia._reference.reference_limit_matrix: the whole mesh refined uniformly
until every semi-sharp tag has decayed, Limit() on the last level, composed
back to the control vertices); the largest entry of their difference and the
reference's time. The unit tests do the same on the shapes that refine in
seconds; this covers the chess pieces and the car (6 levels: 2.4M to 6.4M
faces). The rook (8 levels, 51M faces) is past this machine's memory.
Writes docs/benchmarks/creases-reference.md (unless --no-page).

    python bench/creases_reference.py [--shapes osd_catmark_pawn.obj,...] [--no-page]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import scipy.sparse

import sorpia
from sorpia import _core
from sorpia import _reference  # the test-only module: a `make test` build (SORPIA_BUILD_TESTS)
from sorpia._validate import as_boundary, as_scheme
from sorpia.limit import tags as make_tags
from sorpia.limit import topology as make_topology

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared" / "meshes"
DEFAULT = ("osd_loop_cubes_semisharp.obj,osd_catmark_helmet.obj,osd_catmark_pawn.obj,osd_catmark_bishop.obj,"
           "osd_catmark_car.obj")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", default=DEFAULT, help="comma-separated files in ../shared/meshes")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write the page")
    args = ap.parse_args()
    lines = ["| shape | scheme | vertices | levels | max \\|B - B_ref\\| | reference (s) |", "|---|---|---:|---:|---:|---:|"]
    for name in args.shapes.split(","):
        v, f, tags = sorpia.read_mesh(SHARED / name, tags=True)
        boundary = tags.pop("boundary", "edge-and-corner")
        scheme = "loop" if name.startswith("osd_loop") else "catmull-clark"
        n = len(v)
        B = sorpia.limit_matrix(f, n, boundary=boundary, scheme=scheme, **tags)
        topo = make_topology(f, n, scheme=scheme, warn=False)
        core_tags = make_tags(topo, **tags)
        t0 = time.perf_counter()
        data, indices, indptr = _reference.reference_limit_matrix(
            topo, _core.Rules(scheme=as_scheme(scheme), boundary=as_boundary(boundary), tags=core_tags))
        seconds = time.perf_counter() - t0
        ref = scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))
        levels = math.ceil(core_tags.max_semi_sharpness())
        lines.append(f"| {name} | {scheme} | {n} | {levels} | {abs(B - ref).max():.2e} | {seconds:.1f} |")
        print(lines[-1], flush=True)
    text = "\n".join(["Every row of sorpia's B against OpenSubdiv's whole-mesh refinement and Limit(), with each "
                      "shape's own tags.", ""] + lines)
    if not args.no_page:
        write_page("creases-reference", "Tagged shapes against OpenSubdiv's whole-mesh refinement", text,
                   settings=(ap, args))


if __name__ == "__main__":
    main()
