"""The command line of ``sorpia``: its subcommands, their options and help."""

from __future__ import annotations

import argparse

from .. import __version__, _core
from .._validate import BOUNDARY_RULES, DEFAULT_BOUNDARY
from .._plotting import FACE_BUDGET  # plotting imports matplotlib only when drawing
from ..fair import MAX_LEVELS
from .common import CLI_SCHEMES, DISPLAY_ORDER, FAIR_DEFAULTS, FIT_DEFAULTS
from ..approximate import (DEFAULT_COARSE_ITERATIONS, DEFAULT_COARSE_POINTS, DEFAULT_COARSE_TOL, DEFAULT_FAIRNESS,
                           DEFAULT_ROBUST, DEFAULT_TANGENTIAL, DEFAULT_TOL, ROBUST_LOSSES, SAMPLINGS)
from .approximate import DEFAULT_SAMPLING, STREAM_POINTS, run_approximate
from .compare import run_compare
from .demo import run_demo
from .fit import run_fit
from .info import run_info
from .render import run_render
from .repair import run_repair


def _omega_arg(text: str):
    """--omega: 'auto', 'young' or a number (its range is checked by interpolate)."""
    low = text.strip().lower()
    if low in ("auto", "young"):
        return low
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected auto, young or a number, got {text!r}") from None


def _methods_arg(text: str):
    names = [m.strip().lower() for m in text.split(",") if m.strip()]
    bad = [m for m in names if m not in DISPLAY_ORDER]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"unknown method {', '.join(bad) or '(none)'}: use a comma-separated "
                                         f"list of {','.join(DISPLAY_ORDER)}")
    return list(dict.fromkeys(names))


def _float_arg(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def _int_arg(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


def _positive_int(text: str) -> int:
    value = _int_arg(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1, got {text!r}")
    return value


def _levels_arg(text: str) -> int:
    """--levels: subdivision steps of fair interpolation, 1 to MAX_LEVELS (the core's refinement limit)."""
    value = _int_arg(text)
    if not 1 <= value <= MAX_LEVELS:
        raise argparse.ArgumentTypeError(f"expected 1 to {MAX_LEVELS} subdivision steps, got {text!r}")
    return value


def _level_arg(text: str) -> int:
    value = _int_arg(text)
    if not 0 <= value <= 8:
        raise argparse.ArgumentTypeError(f"expected a level from 0 to 8, got {text!r}")
    return value


def _angle_arg(text: str) -> float:
    value = _float_arg(text)
    if not 0 <= value <= 180:
        raise argparse.ArgumentTypeError(f"expected an angle from 0 to 180 degrees, got {text!r}")
    return value


def _size_arg(text: str):
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, e.g. 1200x1000, got {text!r}") from None
    if not (100 <= w <= 10000 and 100 <= h <= 10000):
        raise argparse.ArgumentTypeError(f"width and height must be 100 to 10000 pixels, got {text!r}")
    return w, h



class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """The default shown after every option that has one (not after flags
    and optional outputs, whose default is simply 'off')."""

    def _get_help_string(self, action):
        if action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


EXIT_HELP = ("exit codes: 0 done; 1 a solve did not reach --tol (it diverged, stopped at --max-iter, or B is "
             "singular and the least-squares answer was written); 2 bad input or options, or not enough memory (one line on stderr); 130 interrupted "
             "(Ctrl-C); 143 terminated (SIGTERM).")
# info and repair solve nothing: no exit code 1.
EXIT_HELP_NO_SOLVE = ("exit codes: 0 done; 2 bad input or options, or not enough memory (one line on stderr); "
                      "130 interrupted (Ctrl-C); 143 terminated (SIGTERM).")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sorpia",
        description="Interpolating subdivision surfaces: move the control vertices of a mesh so that its limit "
        "surface (Loop for triangles, Catmull-Clark for quads and polygons, with OpenSubdiv's creases, corners "
        "and holes) passes through the given vertices (SOR-PIA and the PIA family).",
        epilog=EXIT_HELP + " Run 'sorpia COMMAND --help' for the options of a command.",
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"sorpia {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def command(name, help_text, description, input_arg=True, solves=True):
        p = sub.add_parser(name, help=help_text, description=description,
                           epilog=EXIT_HELP if solves else EXIT_HELP_NO_SOLVE, formatter_class=_Formatter)
        if input_arg:
            p.add_argument("input", metavar="IN", help="input mesh (.obj, .off, .ply, .stl, .usd, .usda, .usdc; "
                           "triangles, quads or any polygons, and OpenSubdiv's sharpness tags in .obj and USD); "
                           "only read")
            p.add_argument("--prim", metavar="PATH", default=None,
                           help="USD input: the mesh prim to read (default: the stage's only mesh)")
        return p

    def triangulate_flag(p, scheme=True):
        p.add_argument("--triangulate", action="store_true",
                       help="split faces of more than 3 vertices into triangles (a quad along its shorter "
                       "diagonal, keeping the mesh manifold where it can)" +
                       (", which makes --scheme auto pick Loop" if scheme else "") +
                       "; hole tags follow their faces' triangles")

    def scheme_options(p):
        p.add_argument("--scheme", choices=CLI_SCHEMES, default="auto",
                       help="subdivision scheme of the limit surface: loop (triangles only), catmull-clark (any "
                       "polygons), or auto: Loop for an all-triangle mesh, Catmull-Clark otherwise")
        p.add_argument("--ignore-tags", action="store_true",
                       help="drop the sharpness tags of an .obj file (OpenSubdiv's 't crease', 't corner', "
                       "'t hole', 't interpolateboundary' lines) or of a USD mesh (and its subdivisionScheme), "
                       "which are used by default")
        p.add_argument("--sharp-angle", type=_angle_arg, metavar="DEG",
                       help="make every edge whose two faces' normals are more than DEG degrees apart an "
                       "infinitely sharp crease (added to the file's creases)")

    def mesh_output(p, what):
        p.add_argument("-o", "--output", metavar="OUT", required=True,
                       help=f"{what} to write (.obj, .off, .ply, .stl or .usd/.usda/.usdc; .stl and USD store "
                       "float32 only)")

    def repair_flag(p, effect):
        p.add_argument("--repair", action="store_true",
                       help="repair the mesh first, as 'sorpia repair' does (duplicate and degenerate faces "
                       "removed, non-manifold edges and bowtie vertices split by copying vertices, orientation "
                       f"made consistent; no vertex moves); {effect}")

    def nonmanifold_flag(p, effect):
        p.add_argument("--nonmanifold", choices=("error", "sharp"), default="error",
                       help="what non-manifold topology gets: error (the default) refuses it; sharp keeps it with "
                       "OpenSubdiv's rules (non-manifold edges infinitely sharp, non-manifold vertices corners) "
                       f"through a manifold split with corner tags, {effect}; OpenSubdiv's documentation calls "
                       "that result undefined")

    def quiet_flag(p):
        p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors and warnings")

    def output_flags(p):
        quiet_flag(p)
        p.add_argument("--force", action="store_true", help="allow an output to overwrite the input file")

    def solver_options(p, with_method=True):
        if with_method:
            p.add_argument("--method", choices=DISPLAY_ORDER, default="auto",
                           help="iteration: auto = sor, falling back to gmres at the first sign that it will not "
                           "reach --tol, and to cgls where B is singular (the least-squares answer); sor = SOR-PIA "
                           "(paper eq. 18), gs = Gauss-Seidel, pia = PIA (eq. 9), wpia = weighted PIA, hss/whss = "
                           "(weighted) Hermitian/skew-Hermitian splitting, cg = conjugate gradients (BiCGSTAB with "
                           "a boundary), gmres = GMRES (any invertible B), cgls = least squares (any B)")
            p.add_argument("--omega", type=_omega_arg, default="auto",
                           help="relaxation of sor (and of auto's sor run): auto (sorpia's measured rule), young "
                           "(paper Remark 1, from the spectral radius of the Jacobi matrix) or a number in (0, 2)")
        fair_text = (f"; with --fair {FAIR_DEFAULTS['tol']:g}, sorpia.fair_interpolate's" if with_method else "")
        p.add_argument("--tol", type=_float_arg, default=None,
                       help="stop when E_k/E_0 < TOL, E_k = max_i |v_i^0 - (B V_k)_i| (paper section 5); default: "
                       f"{FIT_DEFAULTS['tol']:g}, sorpia.interpolate's{fair_text}")
        fair_text = (f"; with --fair {FAIR_DEFAULTS['max_iter']}" if with_method else "")
        p.add_argument("--max-iter", type=_int_arg, default=None, metavar="N",
                       help="stop after N iterations (exit code 1 if TOL was not reached); default: "
                       f"{FIT_DEFAULTS['max_iter']}{fair_text}")
        boundary_option(p, "boundary rule of the limit surface (OpenSubdiv VTX_BOUNDARY_EDGE_AND_CORNER keeps "
                        "one-face corners; EDGE_ONLY smooths them)")

    def boundary_option(p, text):
        p.add_argument("--boundary", choices=BOUNDARY_RULES, default=None,
                       help=f"{text}; default: the file's 't interpolateboundary' tag, else {DEFAULT_BOUNDARY}")

    def threads_option(p, which):
        p.add_argument("--threads", type=_int_arg, default=1, metavar="N",
                       help=f"threads sweeping at once, {which}: vertex index ranges in parallel, then the "
                       "vertices they share (iterations may differ by a few percent from one thread); more "
                       "than the free cores only slows down")

    fit = command("fit", "fit a control mesh whose limit surface interpolates a mesh",
                  "Read a mesh, solve B V = V0 for control vertices V whose limit surface (Loop for triangles, "
                  "Catmull-Clark for quads and polygons: --scheme) passes through the given vertices V0, write "
                  "the control mesh (same faces, same vertex order; in .obj also the tags and the boundary rule "
                  "it was fitted with, and the input's texture coordinates) and, if asked, the tessellated limit "
                  "surface and a JSON report. Every output is checked before the solve. Prints a short summary; "
                  "long runs show progress on stderr.")
    mesh_output(fit, "control mesh")
    solver_options(fit)
    fit.add_argument("--keep-unconverged", action="store_true",
                     help="write the control mesh (and --surface) of a solve that diverged or stopped at --max-iter "
                     "(the iterate of the lowest E_k); without it only --report is written then. The "
                     "least-squares answer on a singular B is always written")
    fit.add_argument("--surface", metavar="SURF",
                     help="also write the limit surface of the control mesh, refined --level times, every vertex "
                     "at its exact limit position: triangles (Loop) or quads (Catmull-Clark; STL holds triangles "
                     "only)")
    fit.add_argument("--level", type=_level_arg, default=3, metavar="L",
                     help="refinement level of --surface: Loop gives 4^L triangles per triangle, Catmull-Clark "
                     "k * 4^(L-1) quads per k-sided face")
    fit.add_argument("--report", metavar="REPORT.json",
                     help="write a JSON report: mesh statistics, method, omega, E_k/E_0 per iteration, seconds "
                     "per phase (read, statistics, fit, write, check, surface)")
    threads_option(fit, "--method auto (its sor run), sor or gs only (refused with other methods, which run on one "
                   "thread)")
    fit.add_argument("--blender", metavar="SCRIPT.py",
                     help="also write a Python script for Blender (bpy) that builds the control mesh with its "
                     "creases and corners as Blender's crease weights and a Subdivision Surface modifier that "
                     "draws the fitted limit surface (Catmull-Clark only: Blender has no Loop)")
    fit.add_argument("--binary", action="store_true", help="write .ply and .stl outputs in binary (faster, "
                     "smaller; PLY keeps float64 either way)")
    fit.add_argument("--fair", action="store_true",
                     help="fair interpolation (Halstead, Kass and DeRose 1993): write a control mesh --levels "
                     "subdivision steps finer (faces and tags as OpenSubdiv's refinement carries them) whose limit "
                     "surface passes through the given vertices (or --targets) and bends least (thin-plate energy, "
                     "plus --membrane); --tol then bounds the energy's relative change over the last iterations (2 to 10) and "
                     "--max-iter its iterations")
    fit.add_argument("--levels", type=_levels_arg, default=None, metavar="N",
                     help=f"--fair: subdivision steps from the input to the fair control mesh, 1 to {MAX_LEVELS} "
                     f"(default {FAIR_DEFAULTS['levels']})")
    fit.add_argument("--membrane", type=_float_arg, default=None, metavar="W",
                     help="--fair: weight of the membrane term beside the thin plate's 1 (default 0)")
    fit.add_argument("--targets", metavar="FILE",
                     help="--fair: interpolate only these vertices (a text file of 0-based vertex indices, '#' "
                     "comments); the others are free")
    scheme_options(fit)
    triangulate_flag(fit)
    repair_flag(fit, "the control mesh is that of the repaired mesh (its extra vertices copy input vertices) and "
                "--report holds the repair report and the vertex map")
    nonmanifold_flag(fit, "whose control mesh is written")
    output_flags(fit)
    fit.set_defaults(func=lambda a: run_fit(
        a.input, a.output, method=a.method, omega=a.omega, tol=a.tol, max_iter=a.max_iter, boundary=a.boundary,
        surface=a.surface, level=a.level, report=a.report, quiet=a.quiet, force=a.force, triangulate=a.triangulate,
        binary=a.binary, threads=a.threads, repair=a.repair, scheme=a.scheme, ignore_tags=a.ignore_tags,
        sharp_angle=a.sharp_angle, nonmanifold=a.nonmanifold, keep_unconverged=a.keep_unconverged, prim=a.prim,
        blender=a.blender, fair=a.fair, levels=a.levels, membrane=a.membrane, targets=a.targets)[0])

    app = command("approximate", "fit a light cage whose limit surface approximates a scan's points",
                  "Read a dense mesh or a point cloud (the data: a mesh's surface, sampled as --sampling says, "
                  "or the cloud's points), take a cage (--cage, a "
                  "mesh file, or --vertices N: the input decimated to N vertices by OpenMesh's Decimater, its triangles "
                  "paired into quads for Catmull-Clark) and move the cage's control vertices so that its limit surface fits the "
                  "points in the least-squares sense (sorpia.approximate: footpoints on the limit surface, the "
                  "normal equations by conjugate gradients or LSPIA, footpoints re-projected after each update). "
                  "Writes the fitted cage (same faces; in .obj also its creases and boundary rule) and, if asked, "
                  "its limit surface and a JSON report with the RMS and max distances per iteration (surface to data: of the "
                  "returned cage). "
                  "Every output is checked before the work. Prints a short summary; the progress line on stderr.",
                  solves=False)
    mesh_output(app, "fitted cage")
    cage_source = app.add_mutually_exclusive_group(required=True)
    cage_source.add_argument("--vertices", type=_positive_int, metavar="N",
                             help="make the cage by decimating the input's triangles to N vertices (where the "
                             "guards stop decimation above N, the cage reached is fitted, with a warning)")
    cage_source.add_argument("--cage", metavar="CAGE", help="the cage as a mesh file (its tags are used); only read")
    app.add_argument("--scheme", choices=CLI_SCHEMES, default="auto",
                     help="subdivision scheme: auto = Loop for a triangle cage (and for --vertices), Catmull-Clark "
                     "otherwise; catmull-clark with --vertices makes a cage of quads (and the few triangles their pairing "
                     "leaves)")
    app.add_argument("--sharp-angle", type=_angle_arg, metavar="DEG",
                     help="make every edge of the cage whose faces' normals are more than DEG degrees apart an "
                     "infinitely sharp crease")
    app.add_argument("--triangulate", action="store_true",
                     help="split the input's faces of more than 3 vertices into triangles (a quad along its shorter "
                     "diagonal) before --vertices decimates them; the data points stay the input's vertices")
    boundary_option(app, "boundary rule of the limit surface")
    app.add_argument("--iterations", type=_positive_int, default=10, metavar="K",
                     help="updates at most, each followed by re-projecting the footpoints")
    app.add_argument("--tol", type=_float_arg, default=DEFAULT_TOL,
                     help="stop when the RMS distance fell by less than this fraction per iteration over the last "
                     "three (and a fresh search of the footpoints finds none closer by more)")
    app.add_argument("--coarse-iterations", type=_int_arg, default=DEFAULT_COARSE_ITERATIONS, metavar="K",
                     help="of the updates, at most the first K from the footpoints of a fixed sample of the points "
                     f"({DEFAULT_COARSE_POINTS:g} per control vertex; none where that is over half the points), at a "
                     f"fraction of the cost; fewer where one lowers the sample's RMS by {100 * DEFAULT_COARSE_TOL:g}%% or "
                     "less, as near the noise floor of noisy data; 0: none (default: %(default)s)")
    app.add_argument("--sampling", choices=("vertices",) + SAMPLINGS, default=None,
                     help="the data of an input mesh with faces: vertices = its vertices, equally weighted; area = "
                     "its vertices weighted by their share of the surface's area; midpoints = its edges' midpoints "
                     f"likewise (default: {DEFAULT_SAMPLING}; a point cloud's points are always equally weighted)")
    app.add_argument("--method", choices=("cg", "lspia"), default="cg",
                     help="the update: cg = conjugate gradients on the normal equations, lspia = LSPIA's iteration")
    app.add_argument("--tangential", type=_float_arg, default=None,
                     help="weight of the distance along the surface: 1 = point distance (slow to converge), 0 = "
                     "distance to the tangent plane (ill-posed alone on scans), between a blend (default: "
                     f"{DEFAULT_TANGENTIAL:g}; 1 with --method lspia)")
    app.add_argument("--fairness", type=_float_arg, default=DEFAULT_FAIRNESS,
                     help="weight of the thin-plate fairness term, relative to the data term: it holds the surface "
                     "where few points hold the cage; 0 for none (default: %(default)r)")
    app.add_argument("--robust", choices=ROBUST_LOSSES, default=DEFAULT_ROBUST,
                     help="the weight of points far from the surface: tukey = none beyond {1:g} times the {0:g}th "
                     "percentile of the distances (outliers do not pull), cauchy = falling as 1/distance beyond {2:g} "
                     "times it, none = least squares (default: %(default)s)".format(
                         100 * _core.robust_options("tukey")[1], _core.robust_options("tukey")[2],
                         _core.robust_options("cauchy")[2]))
    app.add_argument("--surface", metavar="SURF",
                     help="also write the fitted limit surface, refined --level times, every vertex at its exact "
                     "limit position")
    app.add_argument("--level", type=_level_arg, default=3, metavar="L", help="refinement level of --surface")
    app.add_argument("--report", metavar="REPORT.json",
                     help="write a JSON report: the cage, the distances per iteration (surface to data: of the returned "
                     "cage), seconds per phase")
    app.add_argument("--stream", choices=("auto", "yes", "no"), default="auto",
                     help="read the input's points a chunk at a time, never all in memory (out of core: a binary "
                     "little-endian PLY or a .npy (k, 3) array; needs --cage): auto = when the file holds more than "
                     f"{STREAM_POINTS:,} points")
    app.add_argument("--scheduler", metavar="ADDRESS",
                     help="run the fit's chunks of points on the workers of the Dask cluster whose scheduler is at "
                     "ADDRESS (tcp://host:8786; needs dask.distributed: pip install 'sorpia[dask]'); the result is "
                     "the one of the same chunks in one process")
    output_flags(app)
    app.set_defaults(func=lambda a: run_approximate(
        a.input, a.output, vertices=a.vertices, cage=a.cage, scheme=a.scheme, sharp_angle=a.sharp_angle,
        report=a.report, surface=a.surface, level=a.level, iterations=a.iterations, tol=a.tol,
        fairness=a.fairness, tangential=a.tangential, method=a.method, boundary=a.boundary, sampling=a.sampling,
        quiet=a.quiet, force=a.force, prim=a.prim, triangulate=a.triangulate, stream=a.stream,
        robust=a.robust, scheduler=a.scheduler, coarse_iterations=a.coarse_iterations)[0])

    comp = command("compare", "run several methods to one tolerance: the paper's Table 1 and Figure 7",
                   "Run each method on the mesh to the same tolerance and print the paper's Table 1 layout for "
                   "it: omega, iterations to reach E_k/E_0 < 1e-1 ... 1e-10 ('-' = not reached), CPU and wall "
                   "seconds of each method's own solve (the topology and limit operator are built once for all "
                   "methods, their seconds printed below the table). Optionally write the table (Markdown, CSV), every figure (JSON) and "
                   "the convergence plot (Figure 7: log10(E_k/E_0) against k, one line per method).")
    comp.add_argument("--methods", type=_methods_arg, default=",".join(DISPLAY_ORDER), metavar="LIST",
                      help=f"comma-separated methods, from {','.join(DISPLAY_ORDER)} (sor with --omega); a method "
                      "that refuses the mesh is marked in the table and the others still run")
    solver_options(comp, with_method=False)
    comp.add_argument("--omega", type=_omega_arg, default="auto",
                      help="relaxation of sor and of auto's sor run: auto, young or a number in (0, 2)")
    comp.add_argument("--table", metavar="T.md", help="write the table as Markdown")
    comp.add_argument("--csv", metavar="T.csv", help="write the table as CSV")
    comp.add_argument("--plot", metavar="P.png", help="write the convergence plot (paper Figure 7) as PNG")
    comp.add_argument("--json", metavar="J.json", help="write every figure (E_k/E_0 per iteration, timings) as JSON")
    threads_option(comp, "applied to auto (its sor run), sor and gs only (the other methods always run on one "
                   "thread)")
    scheme_options(comp)
    triangulate_flag(comp)
    repair_flag(comp, "--json holds the repair report and the vertex map")
    nonmanifold_flag(comp, "on which every method runs")
    output_flags(comp)
    comp.set_defaults(func=lambda a: run_compare(
        a.input, methods=a.methods, omega=a.omega, tol=a.tol, max_iter=a.max_iter, boundary=a.boundary,
        table=a.table,
        csv_path=a.csv, plot=a.plot, json_path=a.json, quiet=a.quiet, force=a.force, triangulate=a.triangulate,
        threads=a.threads, repair=a.repair, scheme=a.scheme, ignore_tags=a.ignore_tags,
        sharp_angle=a.sharp_angle, nonmanifold=a.nonmanifold, prim=a.prim)[0])

    ren = command("render", "draw the paper's Figure 3 for a mesh (PNG)",
                  "Fit the mesh (--method, auto by default) and draw four shaded panels, the same camera in "
                  "each: (a) the given mesh, (b) its limit surface (Loop or Catmull-Clark: --scheme; it shrinks "
                  "away from the given vertices, red), (c) the control mesh found, given vertices red and "
                  "control vertices blue, (d) the limit "
                  "surface of the control mesh through the red points. Big meshes are drawn at a lower level "
                  "or with part of their faces (--face-budget) so that drawing takes seconds.")
    ren.add_argument("-o", "--output", metavar="FIG.png", required=True, help="PNG image to write")
    ren.add_argument("--level", type=_level_arg, default=3, metavar="L",
                     help="refinement level of the limit surfaces drawn (lowered to fit --face-budget)")
    solver_options(ren)
    ren.add_argument("--size", type=_size_arg, default="1200x1000", metavar="WxH", help="image size in pixels")
    ren.add_argument("--elev", type=float, default=30.0, help="camera elevation in degrees")
    ren.add_argument("--azim", type=float, default=-60.0, help="camera azimuth in degrees")
    ren.add_argument("--up", choices=("x", "y", "z"), default="z",
                     help="the axis drawn vertical (many mesh files, e.g. the Stanford bunny, have y up)")
    ren.add_argument("--face-budget", type=_positive_int, default=FACE_BUDGET, metavar="N",
                     help="most triangles drawn per panel")
    ren.add_argument("--cage", metavar="CAGE",
                     help="approximation instead: IN's vertices are data points, CAGE (a mesh file) is fitted to them "
                     "(sorpia approximate) and the panels show the cage and its limit surface with the data, before "
                     "and after")
    ren.add_argument("--iterations", type=_positive_int, default=10, metavar="K",
                     help="with --cage: the approximation's updates at most")
    threads_option(ren, "--method auto, sor or gs only")
    ren.add_argument("--fair", action="store_true",
                     help="draw plain and fair interpolation side by side (as 'sorpia fit --fair'): the plain "
                     "control mesh and limit surface, then the fair control mesh --levels finer and its surface")
    ren.add_argument("--levels", type=_levels_arg, default=None, metavar="N",
                     help=f"--fair: subdivision steps from the input to the fair control mesh, 1 to {MAX_LEVELS} "
                     f"(default {FAIR_DEFAULTS['levels']})")
    ren.add_argument("--membrane", type=_float_arg, default=None, metavar="W",
                     help="--fair: weight of the membrane term beside the thin plate's 1 (default 0)")
    scheme_options(ren)
    triangulate_flag(ren)
    repair_flag(ren, "the panels show the repaired mesh")
    nonmanifold_flag(ren, "whose panels are drawn")
    output_flags(ren)
    ren.set_defaults(func=lambda a: run_render(
        a.input, a.output, level=a.level, method=a.method, omega=a.omega, tol=a.tol, max_iter=a.max_iter,
        boundary=a.boundary, size=a.size,
        elev=a.elev, azim=a.azim, face_budget=a.face_budget, quiet=a.quiet, force=a.force,
        triangulate=a.triangulate, up=a.up, threads=a.threads, repair=a.repair, scheme=a.scheme,
        ignore_tags=a.ignore_tags, sharp_angle=a.sharp_angle, nonmanifold=a.nonmanifold, prim=a.prim, fair=a.fair,
        levels=a.levels, membrane=a.membrane, cage=a.cage, iterations=a.iterations)[0])

    inf = command("info", "mesh statistics (the paper's Table 2) and whether PIA can run on it",
                  "Print vertices, faces, edges, boundary loops, Euler characteristic, genus, components, "
                  "unreferenced vertices, the valence histogram and the extraordinary vertices (valence other "
                  "than 6 inside, 4 on the boundary for Loop; 4 and 3 for Catmull-Clark; the paper's Table 2), "
                  "the scheme and the tags, and whether PIA can run on the mesh with them, by the checks 'sorpia "
                  "fit' makes with the same options, and if not why (and what --repair would change). Exit code "
                  "0 whenever the file can be read (and, with --repair, repaired), whatever the verdict.",
                  solves=False)
    inf.add_argument("--json", action="store_true", help="print JSON (every extraordinary vertex listed) instead")
    boundary_option(inf, "boundary rule the verdict refers to")
    scheme_options(inf)
    triangulate_flag(inf)
    repair_flag(inf, "the statistics and the verdict are of the repaired mesh (without it, a refused mesh is "
                "told what --repair would change)")
    nonmanifold_flag(inf, "which the statistics and the verdict are of")
    inf.set_defaults(func=lambda a: run_info(a.input, as_json=a.json, boundary=a.boundary,
                                             triangulate=a.triangulate, repair=a.repair, scheme=a.scheme,
                                             ignore_tags=a.ignore_tags, sharp_angle=a.sharp_angle,
                                             nonmanifold=a.nonmanifold, prim=a.prim)[0])

    rep = command("repair", "make a mesh valid for subdivision without moving a vertex",
                  "Read a mesh of triangles, quads or any polygons and write it repaired (sorpia.repair), its "
                  "faces as they were (polygons stay polygons unless --triangulate): a polygon's consecutive "
                  "repeated corners dropped where a polygon of 3 or more vertices is left, other faces with a "
                  "repeated vertex and duplicate faces (either orientation; a closed two-face pillow is kept) "
                  "removed; at an edge of three or more faces the faces "
                  "paired into sheets and the edge's vertices copied per sheet; bowtie vertices split into one "
                  "vertex per fan; where no orientation fits, sheets left unpaired and a twist (a Moebius "
                  "strip) cut along a short path of edges; each connected part oriented consistently. No "
                  "vertex moves; copies are appended after the input vertices. Prints one line per kind of "
                  "change; a valid mesh is written unchanged.",
                  solves=False)
    mesh_output(rep, "repaired mesh")
    rep.add_argument("--report", metavar="REPORT.json",
                     help="write a JSON report: every change with its input faces, edges or vertices, the "
                     "counts, and vertex_map (for every output vertex, the input vertex it copies)")
    triangulate_flag(rep, scheme=False)
    output_flags(rep)
    rep.set_defaults(func=lambda a: run_repair(a.input, a.output, report=a.report, triangulate=a.triangulate,
                                               quiet=a.quiet, force=a.force, prim=a.prim)[0])

    demo = command("demo", "every capability on a built-in sample mesh: interpolation, fair interpolation, "
                   "approximation",
                   "Generate a small sample mesh (a wavy torus with random edge flips: valences 3 to 12, visible "
                   "shrinkage), then run fit (control mesh, limit surface, report), compare (Table 1 as Markdown "
                   "and CSV, Figure 7) and render (Figure 3) on it; fair interpolation (a control mesh one level "
                   "finer through the same vertices, bending least, drawn beside the plain one); and approximate (a "
                   "cage decimated from the sample, fitted to the points of the limit surface that fit wrote, drawn "
                   "with the points before and after); every file into one folder, and print where they are. "
                   "Takes some seconds.", input_arg=False)
    demo.add_argument("--out", metavar="DIR", default=None,
                      help="folder for the files (created if needed; default: a new folder "
                      "sorpia-demo-YYYYMMDD-HHMMSS in the working directory)")
    demo.add_argument("--scheme", choices=CLI_SCHEMES, default="auto",
                      help="the sample mesh and its scheme: loop (a torus of triangles with random edge flips), "
                      "catmull-clark (a torus of quads), or auto (loop)")
    quiet_flag(demo)
    demo.set_defaults(func=lambda a: run_demo(a.out, quiet=a.quiet, scheme=a.scheme))
    return parser
